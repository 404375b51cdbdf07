package main

import (
	"context"
	"encoding/json"
	"net/http"

	"github.com/grpc-ecosystem/grpc-gateway/runtime"
	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
)

// httpStatus maps a gRPC code to the HTTP status a browser or curl expects.
func httpStatus(c codes.Code) int {
	switch c {
	case codes.OK:
		return http.StatusOK
	case codes.InvalidArgument, codes.OutOfRange:
		return http.StatusBadRequest
	case codes.Unauthenticated:
		return http.StatusUnauthorized
	case codes.PermissionDenied:
		return http.StatusForbidden
	case codes.NotFound:
		return http.StatusNotFound
	case codes.AlreadyExists, codes.Aborted, codes.FailedPrecondition:
		return http.StatusConflict
	case codes.ResourceExhausted:
		return http.StatusTooManyRequests
	case codes.Unavailable:
		return http.StatusServiceUnavailable
	case codes.DeadlineExceeded:
		return http.StatusGatewayTimeout
	case codes.Unimplemented:
		return http.StatusNotImplemented
	case codes.Canceled:
		return 499 // the client closed the request
	}
	return http.StatusInternalServerError
}

// The body of every error: the gRPC code (number and name) and the server's message, which
// names the field and value.
type errorBody struct {
	Code    int32  `json:"code"`
	Status  string `json:"status"`
	Message string `json:"message"`
}

func errorOf(err error) (int, errorBody) {
	s, ok := status.FromError(err)
	if !ok {
		s = status.New(codes.Unknown, err.Error())
	}
	return httpStatus(s.Code()), errorBody{int32(s.Code()), codeName(s.Code()), s.Message()}
}

func codeName(c codes.Code) string {
	if c == codes.Canceled {
		return "CANCELLED"
	}
	return toUpperSnake(c.String())
}

// "InvalidArgument" -> "INVALID_ARGUMENT".
func toUpperSnake(s string) string {
	out := make([]byte, 0, len(s)+4)
	for i := 0; i < len(s); i++ {
		ch := s[i]
		if ch >= 'A' && ch <= 'Z' {
			if i > 0 {
				out = append(out, '_')
			}
		} else if ch >= 'a' && ch <= 'z' {
			ch -= 'a' - 'A'
		}
		out = append(out, ch)
	}
	return string(out)
}

func writeError(w http.ResponseWriter, err error) {
	code, body := errorOf(err)
	writeJSONStatus(w, code, body)
}

func writeErrorCode(w http.ResponseWriter, c codes.Code, msg string) {
	writeError(w, status.Error(c, msg))
}

func writeJSONStatus(w http.ResponseWriter, code int, v interface{}) {
	buf, _ := json.Marshal(v)
	h := w.Header()
	h.Del("Content-Length")
	h.Del("Content-Disposition")
	h.Set("Content-Type", "application/json")
	h.Set("X-Content-Type-Options", "nosniff")
	w.WriteHeader(code)
	w.Write(append(buf, '\n'))
}

func init() {
	runtime.HTTPError = func(_ context.Context, _ *runtime.ServeMux, _ runtime.Marshaler,
		w http.ResponseWriter, _ *http.Request, err error) {
		writeError(w, err)
	}
	runtime.OtherErrorHandler = func(w http.ResponseWriter, r *http.Request, msg string, code int) {
		c := codes.Unknown
		switch code {
		case http.StatusNotFound:
			c = codes.NotFound
			msg = "no route " + r.Method + " " + r.URL.Path
		case http.StatusMethodNotAllowed:
			c = codes.Unimplemented
			msg = "method " + r.Method + " not allowed on " + r.URL.Path
		case http.StatusBadRequest:
			c = codes.InvalidArgument
		}
		body := errorBody{int32(c), codeName(c), msg}
		writeJSONStatus(w, code, body)
	}
}
