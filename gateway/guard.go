package main

import (
	"context"
	"crypto/sha256"
	"fmt"
	"io"
	"mime"
	"net"
	"net/http"
	"strings"
	"sync"
	"time"

	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	pb "sheetmesh/v1"
)

// What the gateway checks before it reads a request's body: that a state-changing request
// comes from an allowed origin as JSON (a form or text/plain POST from another site is
// refused), that its body is within its route's limit, and that its token is one the
// server knows. A body that then comes too slowly is cut off. Tokenless clients are told
// apart by address, so that one cannot take every watch.

type connKey struct{}

// withConn keeps each request's connection in its context (http.Server.ConnContext), so
// that a slow body can be given a read deadline.
func withConn(ctx context.Context, c net.Conn) context.Context {
	return context.WithValue(ctx, connKey{}, c)
}

func stateChanging(method string) bool {
	return method == http.MethodPost || method == http.MethodPut || method == http.MethodPatch ||
		method == http.MethodDelete
}

// selfOrigins are the origins of the front-end this gateway serves: its bound address (and,
// on a loopback or any-address listener, the loopback names with its port) and the
// --public_origin ones (its address behind a proxy or a DNS name). Never the request's own
// Host header: a page of evil.example reached through a name that points here sends
// "Origin: http://evil.example:PORT" with "Host: evil.example:PORT", which matched.
func selfOrigins(addr net.Addr, public []string) map[string]bool {
	out := map[string]bool{}
	for _, p := range public {
		out[p] = true
	}
	tcp, ok := addr.(*net.TCPAddr)
	if !ok {
		return out
	}
	port := fmt.Sprint(tcp.Port)
	out["http://"+net.JoinHostPort(tcp.IP.String(), port)] = true
	if tcp.IP.IsLoopback() || tcp.IP.IsUnspecified() {
		for _, h := range []string{"localhost", "127.0.0.1", "::1"} {
			out["http://"+net.JoinHostPort(h, port)] = true
		}
	}
	return out
}

// originAllowed is whether a state-changing request from `origin` may go on: no Origin (a
// client that is no browser), the gateway's own front-end (selfOrigins), or --cors_origins.
func (g *gateway) originAllowed(origin string) bool {
	origin = strings.TrimRight(origin, "/")
	if origin == "" || g.self[origin] {
		return true
	}
	for _, o := range g.o.corsOrigins {
		if o == "*" || o == origin {
			return true
		}
	}
	return false
}

// bodyLimit is the largest body the route of r may carry, and the flag that sets it.
func (g *gateway) bodyLimit(r *http.Request) (int64, string) {
	if uploadRoute.MatchString(r.URL.Path) {
		return g.o.maxChunkBytes, "--max_chunk_mb"
	}
	if r.URL.Path == "/v1/uploads:write" {
		return g.o.maxChunkBytes*4/3 + 1<<20, "--max_chunk_mb" // JSON pieces, bytes in base64
	}
	return g.o.maxJSONBytes, "--max_json_mb"
}

// endUnread marks a request refused before its body was read: the connection ends with the
// answer. (Otherwise the server would read what is left of a small body to keep the
// connection, waiting as long as a trickling client likes.)
func endUnread(w http.ResponseWriter, r *http.Request) {
	w.Header().Set("Connection", "close")
	if conn, ok := r.Context().Value(connKey{}).(net.Conn); ok {
		conn.SetReadDeadline(time.Now())
	}
}

// guard answers a request it refuses and returns false; otherwise it wraps the body in
// its limits and returns true.
func (g *gateway) guard(w http.ResponseWriter, r *http.Request) bool {
	if r.URL.Query().Has("access_token") {
		endUnread(w, r)
		writeErrorCode(w, codes.InvalidArgument, "a token in a URL (access_token) is not taken: "+
			"send it as 'Authorization: Bearer <token>', or use a link from POST "+
			"/v1/jobs/{id}/artifacts/{name}:link")
		return false
	}
	if !stateChanging(r.Method) {
		return true
	}
	if origin := r.Header.Get("Origin"); !g.originAllowed(origin) {
		endUnread(w, r)
		writeErrorCode(w, codes.PermissionDenied, fmt.Sprintf(
			"%s %s from origin %s, which is neither this gateway's address nor in --public_origin "+
				"or --cors_origins", r.Method, r.URL.Path, origin))
		return false
	}
	upload := uploadRoute.MatchString(r.URL.Path)
	if !upload && r.Method != http.MethodDelete {
		// A browser sends a cross-site form or text/plain POST without asking first; JSON it
		// does not.
		mt, _, _ := mime.ParseMediaType(r.Header.Get("Content-Type"))
		if mt != "application/json" && mt != "application/x-ndjson" {
			endUnread(w, r)
			writeJSONStatus(w, http.StatusUnsupportedMediaType, errorBody{int32(codes.InvalidArgument),
				"INVALID_ARGUMENT", fmt.Sprintf("%s %s needs Content-Type: application/json (got %q)",
					r.Method, r.URL.Path, r.Header.Get("Content-Type"))})
			return false
		}
	}
	limit, flag := g.bodyLimit(r)
	if r.ContentLength > limit {
		endUnread(w, r)
		writeJSONStatus(w, http.StatusRequestEntityTooLarge, errorBody{int32(codes.ResourceExhausted),
			"RESOURCE_EXHAUSTED", fmt.Sprintf("a body of %d bytes exceeds the %d bytes %s %s may carry "+
				"(the gateway's %s): send smaller chunks", r.ContentLength, limit, r.Method, r.URL.Path, flag)})
		return false
	}
	if err := g.tokens.check(r); err != nil {
		endUnread(w, r)
		writeError(w, err)
		return false
	}
	conn, _ := r.Context().Value(connKey{}).(net.Conn)
	r.Body = &slowBodyGuard{body: http.MaxBytesReader(w, r.Body, limit), conn: conn,
		start: time.Now(), idle: g.o.bodyIdle, minRate: g.o.bodyMinRate, grace: g.o.bodyGrace}
	return true
}

// slowBodyGuard ends a body whose bytes stop coming for `idle`, or come slower than
// minRate bytes a second on average once `grace` has passed.
type slowBodyGuard struct {
	body    io.ReadCloser
	conn    net.Conn
	start   time.Time
	read    int64
	idle    time.Duration
	grace   time.Duration
	minRate float64
}

func (s *slowBodyGuard) Read(p []byte) (int, error) {
	if s.conn != nil {
		s.conn.SetReadDeadline(time.Now().Add(s.idle))
	}
	n, err := s.body.Read(p)
	s.read += int64(n)
	if err != nil {
		if s.conn != nil {
			s.conn.SetReadDeadline(time.Time{})
		}
		if ne, ok := err.(net.Error); ok && ne.Timeout() {
			return n, fmt.Errorf("no byte of the body came for %v", s.idle)
		}
		return n, err
	}
	if elapsed := time.Since(s.start); elapsed > s.grace &&
		float64(s.read) < s.minRate*(elapsed-s.grace).Seconds() {
		if s.conn != nil {
			s.conn.SetReadDeadline(time.Now()) // the connection ends with the request
		}
		return n, fmt.Errorf("the body came at %.0f bytes/s, below the gateway's %.0f",
			float64(s.read)/elapsed.Seconds(), s.minRate)
	}
	return n, nil
}

func (s *slowBodyGuard) Close() error { return s.body.Close() }

// tokenCheck asks the server whether a request's token is one it knows (an empty
// FindMissingBlobs: authenticated, and nothing else to do), remembering the answer for a
// little while so that a burst of chunks asks once.
type tokenCheck struct {
	blobs pb.BlobServiceClient
	ttl   time.Duration
	mu    sync.Mutex
	known map[[32]byte]time.Time
}

func (t *tokenCheck) check(r *http.Request) error {
	key := sha256.Sum256([]byte(r.Header.Get("Authorization")))
	now := time.Now()
	t.mu.Lock()
	until, ok := t.known[key]
	t.mu.Unlock()
	if ok && now.Before(until) {
		return nil
	}
	ctx, cancel := context.WithTimeout(outgoing(r), 10*time.Second)
	defer cancel()
	if _, err := t.blobs.FindMissingBlobs(ctx, &pb.FindMissingBlobsRequest{}); err != nil {
		return err
	}
	t.mu.Lock()
	if len(t.known) > 10000 {
		t.known = map[[32]byte]time.Time{}
	}
	t.known[key] = now.Add(t.ttl)
	t.mu.Unlock()
	return nil
}

// watchQuota counts the open watches of each client address.
type watchQuota struct {
	limit int
	mu    sync.Mutex
	open  map[string]int
}

func clientAddress(r *http.Request) string {
	host, _, err := net.SplitHostPort(r.RemoteAddr)
	if err != nil {
		return r.RemoteAddr
	}
	return host
}

// acquire takes a place for one more watch of r's client; the function it returns frees
// it. An error when the client has `limit` open already.
func (q *watchQuota) acquire(r *http.Request) (func(), error) {
	who := clientAddress(r)
	q.mu.Lock()
	defer q.mu.Unlock()
	if q.open[who] >= q.limit {
		return nil, status.Error(codes.ResourceExhausted, fmt.Sprintf(
			"%s has %d watches open, the gateway's limit per client (--max_watches_per_client)",
			who, q.open[who]))
	}
	q.open[who]++
	return func() {
		q.mu.Lock()
		defer q.mu.Unlock()
		if q.open[who]--; q.open[who] <= 0 {
			delete(q.open, who)
		}
	}, nil
}
