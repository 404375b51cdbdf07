package main

import (
	"bytes"
	"io"
	"net/http"
	"strings"

	pb "sheetmesh/v1"
)

// watch answers GET /v1/jobs/{id}:watch: the job at once and at every change until it
// finishes, as Server-Sent Events (event "job", then "end"; "error" with the error body)
// when the request accepts text/event-stream or says ?format=sse, else as
// newline-delimited JSON ({"result": ...} per line, {"error": ...} on failure).
func (g *gateway) watch(w http.ResponseWriter, r *http.Request, job string) {
	sse := strings.Contains(r.Header.Get("Accept"), "text/event-stream") || r.URL.Query().Get("format") == "sse"
	flusher, _ := w.(http.Flusher)
	ctx := outgoing(r)
	stream, err := g.jobs.WatchJob(ctx, &pb.WatchJobRequest{Name: job})
	var first *pb.WatchJobResponse
	if err == nil {
		first, err = stream.Recv()
	}
	if err != nil {
		writeError(w, err) // before any event: a plain HTTP error
		return
	}
	h := w.Header()
	h.Set("Cache-Control", "no-cache")
	h.Set("X-Accel-Buffering", "no")
	if sse {
		h.Set("Content-Type", "text/event-stream")
	} else {
		h.Set("Content-Type", "application/x-ndjson")
	}
	w.WriteHeader(http.StatusOK)
	send := func(event string, body []byte) bool {
		var b bytes.Buffer
		if sse {
			b.WriteString("event: " + event + "\ndata: ")
			b.Write(body)
			b.WriteString("\n\n")
		} else if event == "job" {
			b.WriteString(`{"result":`)
			b.Write(body)
			b.WriteString("}\n")
		} else if event == "error" {
			b.WriteString(`{"error":`)
			b.Write(body)
			b.WriteString("}\n")
		} else {
			return true
		}
		if _, err := w.Write(b.Bytes()); err != nil {
			return false
		}
		if flusher != nil {
			flusher.Flush()
		}
		return true
	}
	for msg := first; ; {
		body, merr := strictJSON{}.Marshal(msg)
		if merr != nil || !send("job", body) {
			return
		}
		if msg, err = stream.Recv(); err != nil {
			break
		}
	}
	if err == io.EOF {
		send("end", []byte("{}"))
		return
	}
	if r.Context().Err() != nil {
		return // the client went
	}
	_, e := errorOf(err)
	body, _ := strictJSON{}.Marshal(e)
	send("error", body)
}
