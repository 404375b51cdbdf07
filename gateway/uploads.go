package main

import (
	"fmt"
	"io"
	"net/http"
	"strconv"

	"google.golang.org/grpc/codes"
	pb "sheetmesh/v1"
)

const pieceBytes = 1 << 20 // the server's largest WriteRequest piece

// upload answers PUT /v1/uploads/{uuid}/blobs/{hash}/{size}?offset=N[&finish=true]: the
// body is the blob's bytes from N on, sent to the server as one Write stream. A browser
// sends a file in chunks, asks GET .../{size}:status after a break and goes on from the
// committed size; the last chunk carries finish=true (or reaches the size) and the server
// checks the digest. The answer is {"committed_size": N, "complete": bool}.
func (g *gateway) upload(w http.ResponseWriter, r *http.Request, uuid, hash, sizeText string) {
	resource := fmt.Sprintf("uploads/%s/blobs/%s/%s", uuid, hash, sizeText)
	size, err := strconv.ParseInt(sizeText, 10, 64)
	if err != nil || size < 0 {
		writeErrorCode(w, codes.InvalidArgument, fmt.Sprintf("size %q in %s is not a byte count", sizeText, resource))
		return
	}
	q := r.URL.Query()
	offset, err := strconv.ParseInt(q.Get("offset"), 10, 64)
	if q.Get("offset") == "" {
		offset, err = 0, nil
	}
	if err != nil || offset < 0 || offset > size {
		writeErrorCode(w, codes.InvalidArgument, fmt.Sprintf("offset=%q: must be a byte offset within [0, %d]", q.Get("offset"), size))
		return
	}
	finish := q.Get("finish") == "true" || q.Get("finish") == "1"
	if f := q.Get("finish"); f != "" && f != "true" && f != "false" && f != "1" && f != "0" {
		writeErrorCode(w, codes.InvalidArgument, fmt.Sprintf("finish=%q: must be true or false", f))
		return
	}
	if r.ContentLength > g.o.maxChunkBytes {
		writeErrorCode(w, codes.ResourceExhausted, fmt.Sprintf(
			"a chunk of %d bytes exceeds the gateway's %d-byte limit (--max_chunk_mb): send smaller chunks",
			r.ContentLength, g.o.maxChunkBytes))
		return
	}
	body := http.MaxBytesReader(w, r.Body, g.o.maxChunkBytes)
	stream, err := g.blobs.Write(outgoing(r))
	if err != nil {
		writeError(w, err)
		return
	}
	buf := make([]byte, pieceBytes)
	at := offset
	first := true
	for {
		n, rerr := io.ReadFull(body, buf)
		if rerr != nil && rerr != io.EOF && rerr != io.ErrUnexpectedEOF {
			// The browser went or sent too much: keep what was written, say so.
			stream.CloseAndRecv()
			writeErrorCode(w, codes.InvalidArgument, fmt.Sprintf("reading the chunk at offset %d: %v", at, rerr))
			return
		}
		last := rerr != nil
		req := &pb.WriteRequest{WriteOffset: at, Data: buf[:n], FinishWrite: last && (finish || at+int64(n) == size)}
		if first {
			req.ResourceName = resource
			first = false
		}
		if n > 0 || req.FinishWrite || at == offset {
			if err := stream.Send(req); err != nil {
				break // the server ended the stream: CloseAndRecv says why
			}
		}
		at += int64(n)
		if last {
			break
		}
	}
	resp, err := stream.CloseAndRecv()
	if err != nil {
		writeError(w, err)
		return
	}
	st, err := g.blobs.QueryWriteStatus(outgoing(r), &pb.QueryWriteStatusRequest{ResourceName: resource})
	complete := err == nil && st.Complete
	writeJSONStatus(w, http.StatusOK, map[string]interface{}{
		"resource_name": resource, "committed_size": resp.CommittedSize, "complete": complete})
}
