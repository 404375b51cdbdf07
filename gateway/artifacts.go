package main

import (
	"fmt"
	"io"
	"math"
	"mime"
	"net/http"
	"strconv"
	"strings"

	"google.golang.org/grpc/codes"
	pb "sheetmesh/v1"
)

// byteRange is [start, end) of a blob.
type byteRange struct{ start, end int64 }

// parseRange reads a "Range: bytes=..." header for a blob of `size` bytes: one range
// (multipart answers are not offered). ok=false means unsatisfiable (416); a header that
// is not a bytes range, or asks for several, is ignored (the whole blob, as RFC 9110
// allows). Positions too large for 64 bits are as large as any: past the end.
func parseRange(h string, size int64) (r byteRange, partial, ok bool) {
	whole := byteRange{0, size}
	if h == "" || !strings.HasPrefix(h, "bytes=") || strings.Contains(h, ",") {
		return whole, false, true
	}
	spec := strings.TrimSpace(strings.TrimPrefix(h, "bytes="))
	dash := strings.IndexByte(spec, '-')
	if dash < 0 {
		return whole, false, true
	}
	first, last := strings.TrimSpace(spec[:dash]), strings.TrimSpace(spec[dash+1:])
	if first == "" { // the last N bytes
		n, valid := position(last)
		if !valid {
			return whole, false, true
		}
		if n == 0 || size == 0 {
			return r, false, false
		}
		if n > size {
			n = size
		}
		return byteRange{size - n, size}, true, true
	}
	a, valid := position(first)
	if !valid {
		return whole, false, true
	}
	if a >= size {
		return r, false, false
	}
	b := size - 1
	if last != "" {
		if b, valid = position(last); !valid || b < a {
			return whole, false, true
		}
		if b >= size {
			b = size - 1
		}
	}
	return byteRange{a, b + 1}, true, true
}

// position reads a byte position of a Range: decimal digits, any number of them (a value
// beyond 64 bits is math.MaxInt64). valid=false for anything else.
func position(s string) (int64, bool) {
	if s == "" {
		return 0, false
	}
	for i := 0; i < len(s); i++ {
		if s[i] < '0' || s[i] > '9' {
			return 0, false
		}
	}
	n, err := strconv.ParseInt(s, 10, 64)
	if err != nil {
		return math.MaxInt64, true // only digits: too large
	}
	return n, true
}

// download answers GET /v1/jobs/{id}/artifacts/{name}: the artifact's bytes with its
// media type, length and file name, in part where a Range asks for it.
func (g *gateway) download(w http.ResponseWriter, r *http.Request, job, name string) {
	ctx := outgoing(r)
	j, err := g.jobs.GetJob(ctx, &pb.GetJobRequest{Name: job})
	if err != nil {
		writeError(w, err)
		return
	}
	var art *pb.Artifact
	var names []string
	for _, a := range j.Artifacts {
		names = append(names, a.Name)
		if a.Name == name {
			art = a
		}
	}
	if art == nil {
		if j.State == pb.JobState_QUEUED || j.State == pb.JobState_RUNNING {
			writeErrorCode(w, codes.FailedPrecondition, fmt.Sprintf(
				"%s is %s: artifacts come when it has ended", job, j.State))
			return
		}
		if len(names) == 0 {
			writeErrorCode(w, codes.FailedPrecondition, fmt.Sprintf(
				"%s is %s and kept no artifact", job, j.State))
			return
		}
		writeErrorCode(w, codes.NotFound, fmt.Sprintf("%s has no artifact %q (it has: %s)",
			job, name, strings.Join(names, ", ")))
		return
	}
	size := art.Digest.GetSizeBytes()
	rg, partial, ok := parseRange(r.Header.Get("Range"), size)
	h := w.Header()
	h.Set("Accept-Ranges", "bytes")
	h.Set("ETag", `"`+art.Digest.GetHash()+`"`)
	h.Set("X-Content-SHA256", art.Digest.GetHash())
	if !ok {
		h.Set("Content-Range", fmt.Sprintf("bytes */%d", size))
		writeJSONStatus(w, http.StatusRequestedRangeNotSatisfiable, errorBody{int32(codes.OutOfRange),
			"OUT_OF_RANGE", fmt.Sprintf("range %q is outside %s's %d bytes", r.Header.Get("Range"), name, size)})
		return
	}
	// Stream from the server before committing to a status: a refusal is still an error.
	var stream pb.BlobService_ReadClient
	var first *pb.ReadResponse
	if rg.end > rg.start && r.Method != http.MethodHead {
		stream, err = g.blobs.Read(ctx, &pb.ReadRequest{Digest: art.Digest, ReadOffset: rg.start,
			ReadLimit: rg.end - rg.start})
		if err == nil {
			first, err = stream.Recv()
		}
		if err != nil && err != io.EOF {
			writeError(w, err)
			return
		}
	}
	mediaType := art.MediaType
	if mediaType == "" {
		mediaType = "application/octet-stream"
	}
	h.Set("Content-Type", mediaType)
	h.Set("Content-Length", strconv.FormatInt(rg.end-rg.start, 10))
	h.Set("Content-Disposition", mime.FormatMediaType("attachment", map[string]string{"filename": name}))
	h.Set("X-Content-Type-Options", "nosniff")
	if partial {
		h.Set("Content-Range", fmt.Sprintf("bytes %d-%d/%d", rg.start, rg.end-1, size))
		w.WriteHeader(http.StatusPartialContent)
	} else {
		w.WriteHeader(http.StatusOK)
	}
	if r.Method == http.MethodHead || first == nil {
		return
	}
	for {
		if _, err := w.Write(first.Data); err != nil {
			return // the client went
		}
		if first, err = stream.Recv(); err != nil {
			return // EOF, or a broken read: the length tells the client
		}
	}
}
