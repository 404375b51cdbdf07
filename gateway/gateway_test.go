package main

import (
	"math"
	"net"
	"strings"
	"testing"
	"time"

	"google.golang.org/grpc/codes"
	pb "sheetmesh/v1"
)

func TestRanges(t *testing.T) {
	for _, c := range []struct {
		header           string
		size             int64
		start, end       int64
		partial, satisfy bool
	}{
		{"", 100, 0, 100, false, true},
		{"bytes=0-9", 100, 0, 10, true, true},
		{"bytes=90-", 100, 90, 100, true, true},
		{"bytes=90-500", 100, 90, 100, true, true},
		{"bytes=-10", 100, 90, 100, true, true},
		{"bytes=-500", 100, 0, 100, true, true},
		{"bytes=100-", 100, 0, 0, false, false},
		{"bytes=-0", 100, 0, 0, false, false},
		{"bytes=5-2", 100, 0, 100, false, true},     // invalid: the whole blob
		{"bytes=0-1,5-6", 100, 0, 100, false, true}, // several: the whole blob
		{"items=0-1", 100, 0, 100, false, true},
		// Positions past 64 bits: as large as any.
		{"bytes=99999999999999999999-", 100, 0, 0, false, false},
		{"bytes=10-99999999999999999999", 100, 10, 100, true, true},
		{"bytes=-99999999999999999999", 100, 0, 100, true, true},
		{"bytes=+5-9", 100, 0, 100, false, true}, // not digits: the whole blob
	} {
		r, partial, ok := parseRange(c.header, c.size)
		if ok != c.satisfy || (ok && (r.start != c.start || r.end != c.end || partial != c.partial)) {
			t.Errorf("%q of %d: got [%d, %d) partial %v ok %v", c.header, c.size, r.start, r.end, partial, ok)
		}
	}
}

func TestCodesMapToHTTP(t *testing.T) {
	want := map[codes.Code]int{codes.InvalidArgument: 400, codes.Unauthenticated: 401, codes.PermissionDenied: 403,
		codes.NotFound: 404, codes.FailedPrecondition: 409, codes.AlreadyExists: 409, codes.ResourceExhausted: 429,
		codes.Unavailable: 503, codes.Internal: 500, codes.DeadlineExceeded: 504}
	for c, h := range want {
		if got := httpStatus(c); got != h {
			t.Errorf("%v: %d, want %d", c, got, h)
		}
	}
	if codeName(codes.InvalidArgument) != "INVALID_ARGUMENT" || codeName(codes.Canceled) != "CANCELLED" ||
		codeName(codes.NotFound) != "NOT_FOUND" {
		t.Errorf("code names: %s %s %s", codeName(codes.InvalidArgument), codeName(codes.Canceled), codeName(codes.NotFound))
	}
}

func TestUnknownFieldsAreRefused(t *testing.T) {
	var req pb.CreateJobRequest
	err := strictJSON{}.Unmarshal([]byte(`{"request_id": "a", "colour": "red"}`), &req)
	if err == nil || !strings.Contains(err.Error(), "colour") || !strings.Contains(err.Error(), "sheetmesh.v1.CreateJobRequest") {
		t.Fatalf("unknown field: %v", err)
	}
	if err := (strictJSON{}).Unmarshal([]byte(`{"request_id": "a", "parameters": {"r": 7, "volume_mesh": true}}`), &req); err != nil {
		t.Fatal(err)
	}
	if req.GetParameters().GetR() != 7 || !req.GetParameters().GetVolumeMesh() {
		t.Fatalf("parsed %v", req.GetParameters())
	}
	out, err := strictJSON{}.Marshal(&req)
	if err != nil || !strings.Contains(string(out), `"request_id":"a"`) {
		t.Fatalf("marshal: %s %v", out, err)
	}
}

func TestFlags(t *testing.T) {
	o, err := parseFlags([]string{"--cors_origins=https://a.example/, *", "--max_chunk_mb=8"})
	if err != nil || len(o.corsOrigins) != 2 || o.corsOrigins[0] != "https://a.example" || o.maxChunkBytes != 8<<20 {
		t.Fatalf("%+v %v", o, err)
	}
	if _, err := parseFlags([]string{"--version"}); err != errVersion {
		t.Errorf("--version: %v", err)
	}
	for _, bad := range [][]string{{"--max_chunk_mb=0"}, {"--server_ca=x.pem"}, {"stray"}, {"--no_such_flag"}} {
		if _, err := parseFlags(bad); err == nil {
			t.Errorf("%v accepted", bad)
		}
	}
}

func TestLinksOpenOneArtifactUntilTheyExpire(t *testing.T) {
	s, err := newLinkSealer("", time.Minute)
	if err != nil {
		t.Fatal(err)
	}
	now := time.Now()
	text, err := s.seal(sealedLink{Auth: "Bearer secret-token", Job: "jobs/1", Name: "a.png",
		Expires: now.Add(time.Minute).Unix()})
	if err != nil {
		t.Fatal(err)
	}
	if strings.Contains(text, "secret") {
		t.Errorf("the token shows in the link: %s", text)
	}
	if l, err := s.open(text, "jobs/1", "a.png", now); err != nil || l.Auth != "Bearer secret-token" {
		t.Errorf("a fresh link: %v %+v", err, l)
	}
	for _, c := range []struct {
		job, name string
		at        time.Time
		want      string
	}{
		{"jobs/2", "a.png", now, "is for jobs/1"},
		{"jobs/1", "b.png", now, "is for jobs/1"},
		{"jobs/1", "a.png", now.Add(2 * time.Minute), "expired"},
	} {
		if _, err := s.open(text, c.job, c.name, c.at); err == nil || !strings.Contains(err.Error(), c.want) {
			t.Errorf("%s %s at +%v: %v, want %q", c.job, c.name, c.at.Sub(now), err, c.want)
		}
	}
	other, _ := newLinkSealer("", time.Minute)
	if _, err := other.open(text, "jobs/1", "a.png", now); err == nil {
		t.Error("another gateway's key opened the link")
	}
	if _, err := s.open(text[:len(text)-2]+"AA", "jobs/1", "a.png", now); err == nil {
		t.Error("a changed link opened")
	}
}

func TestOriginsAndPositions(t *testing.T) {
	// Hardening, third round: the request's own Host header decided, so a page of
	// evil.example:8080 resolving here (DNS rebinding) passed as the gateway's own.
	addr := &net.TCPAddr{IP: net.ParseIP("127.0.0.1"), Port: 8080}
	g := &gateway{o: options{corsOrigins: []string{"https://lab.example"}},
		self: selfOrigins(addr, []string{"https://sheetmesh.lab.example"})}
	for origin, want := range map[string]bool{"": true, "http://127.0.0.1:8080": true,
		"http://localhost:8080": true, "http://localhost:8080/": true, "http://[::1]:8080": true,
		"https://sheetmesh.lab.example": true, "https://lab.example": true,
		"http://evil.example:8080": false, "https://evil.example": false,
		"http://127.0.0.1:9090": false, "http://gw:8080": false} {
		if got := g.originAllowed(origin); got != want {
			t.Errorf("origin %q: %v, want %v", origin, got, want)
		}
	}
	wide := selfOrigins(&net.TCPAddr{IP: net.ParseIP("10.0.0.5"), Port: 80}, nil)
	if !wide["http://10.0.0.5:80"] || wide["http://localhost:80"] {
		t.Errorf("a gateway on 10.0.0.5:80 takes %v", wide)
	}
	if _, err := parseFlags([]string{"--public_origin=sheetmesh.lab.example"}); err == nil {
		t.Error("an origin without its scheme was taken")
	}
	if n, ok := position("99999999999999999999999"); !ok || n != math.MaxInt64 {
		t.Errorf("a position past 64 bits: %d %v", n, ok)
	}
	if _, ok := position("-5"); ok {
		t.Error("a signed position was taken")
	}
}
