package main

import (
	"context"
	"net/http"
	"regexp"
	"strings"
	"time"

	"github.com/grpc-ecosystem/grpc-gateway/runtime"
	"google.golang.org/grpc"
	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/metadata"
	pb "sheetmesh/v1"
)

type gateway struct {
	ctx     context.Context // ends with the process: watches stop
	jobs    pb.JobServiceClient
	blobs   pb.BlobServiceClient
	api     *runtime.ServeMux
	web     http.Handler
	openAPI []byte
	o       options
	tokens  *tokenCheck
	links   *linkSealer
	watches *watchQuota
	self    map[string]bool // the front-end's own origins (selfOrigins), set once listening
}

var (
	linkRoute     = regexp.MustCompile(`^/v1/jobs/([A-Za-z0-9_-]+)/artifacts/([^/]+):link$`)
	artifactRoute = regexp.MustCompile(`^/v1/jobs/([A-Za-z0-9_-]+)/artifacts/([^/]+)$`)
	watchRoute    = regexp.MustCompile(`^/v1/jobs/([A-Za-z0-9_-]+):watch$`)
	uploadRoute   = regexp.MustCompile(`^/v1/uploads/([A-Za-z0-9_-]+)/blobs/([0-9a-f]{64})/([0-9]+)$`)
)

func newGateway(ctx context.Context, conn *grpc.ClientConn, o options) (*gateway, error) {
	api := runtime.NewServeMux(
		runtime.WithMarshalerOption(runtime.MIMEWildcard, strictJSON{}),
	)
	for _, register := range []func(context.Context, *runtime.ServeMux, *grpc.ClientConn) error{
		pb.RegisterJobServiceHandler, pb.RegisterBlobServiceHandler, pb.RegisterVolumeServiceHandler,
	} {
		if err := register(ctx, api, conn); err != nil {
			return nil, err
		}
	}
	web, err := webHandler(o.webRoot)
	if err != nil {
		return nil, err
	}
	doc, err := openAPIDocument()
	if err != nil {
		return nil, err
	}
	links, err := newLinkSealer(o.linkKeyFile, o.linkTTL)
	if err != nil {
		return nil, err
	}
	blobs := pb.NewBlobServiceClient(conn)
	g := &gateway{ctx: ctx, jobs: pb.NewJobServiceClient(conn), blobs: blobs,
		api: api, web: web, openAPI: doc, o: o,
		tokens:  &tokenCheck{blobs: blobs, ttl: 30 * time.Second, known: map[[32]byte]time.Time{}},
		links:   links,
		watches: &watchQuota{limit: o.maxWatchesPerClient, open: map[string]int{}}}
	return g, nil
}

// outgoing is the request's context with its bearer token for the server.
func outgoing(r *http.Request) context.Context {
	if auth := r.Header.Get("Authorization"); auth != "" {
		return metadata.AppendToOutgoingContext(r.Context(), "authorization", auth)
	}
	return r.Context()
}

func (g *gateway) ServeHTTP(w http.ResponseWriter, r *http.Request) {
	if !g.cors(w, r) {
		return
	}
	p := r.URL.Path
	switch {
	case p == "/openapi.json" || p == "/v1/openapi.json":
		w.Header().Set("Content-Type", "application/json")
		w.Write(g.openAPI)
	case p == "/healthz":
		w.Header().Set("Content-Type", "text/plain")
		w.Write([]byte("ok\n"))
	case strings.HasPrefix(p, "/v1/"):
		if !g.guard(w, r) {
			return
		}
		if m := linkRoute.FindStringSubmatch(p); m != nil {
			if onlyMethods(w, r, http.MethodPost) {
				g.makeLink(w, r, "jobs/"+m[1], m[2])
			}
			return
		}
		if m := artifactRoute.FindStringSubmatch(p); m != nil {
			if onlyMethods(w, r, http.MethodGet, http.MethodHead) && g.fromLink(w, r, "jobs/"+m[1], m[2]) {
				g.download(w, r, "jobs/"+m[1], m[2])
			}
			return
		}
		if m := watchRoute.FindStringSubmatch(p); m != nil {
			if onlyMethods(w, r, http.MethodGet) {
				release, err := g.watches.acquire(r)
				if err != nil {
					writeError(w, err)
					return
				}
				defer release()
				g.watch(w, r, "jobs/"+m[1])
			}
			return
		}
		if m := uploadRoute.FindStringSubmatch(p); m != nil && r.Method != http.MethodGet {
			if onlyMethods(w, r, http.MethodPut) {
				g.upload(w, r, m[1], m[2], m[3])
			}
			return
		}
		g.api.ServeHTTP(w, r)
	default:
		g.web.ServeHTTP(w, r)
	}
}

func onlyMethods(w http.ResponseWriter, r *http.Request, methods ...string) bool {
	for _, m := range methods {
		if r.Method == m {
			return true
		}
	}
	w.Header().Set("Allow", strings.Join(methods, ", "))
	writeJSONStatus(w, http.StatusMethodNotAllowed, errorBody{12, "UNIMPLEMENTED",
		"method " + r.Method + " not allowed on " + r.URL.Path + " (allowed: " + strings.Join(methods, ", ") + ")"})
	return false
}

// cors answers a browser's preflight and marks allowed origins; false when the request is
// fully answered.
func (g *gateway) cors(w http.ResponseWriter, r *http.Request) bool {
	origin := r.Header.Get("Origin")
	if origin == "" || len(g.o.corsOrigins) == 0 {
		return true
	}
	allowed := false
	for _, o := range g.o.corsOrigins {
		allowed = allowed || o == "*" || o == origin
	}
	if !allowed {
		if r.Method == http.MethodOptions {
			writeErrorCode(w, codes.PermissionDenied, "origin "+origin+" is not in --cors_origins")
			return false
		}
		return true // the browser withholds the answer
	}
	h := w.Header()
	h.Set("Access-Control-Allow-Origin", origin)
	h.Add("Vary", "Origin")
	h.Set("Access-Control-Expose-Headers", "Content-Length, Content-Range, Content-Disposition, Accept-Ranges")
	if r.Method == http.MethodOptions && r.Header.Get("Access-Control-Request-Method") != "" {
		h.Set("Access-Control-Allow-Methods", "GET, HEAD, POST, PUT, DELETE, OPTIONS")
		h.Set("Access-Control-Allow-Headers", "Authorization, Content-Type, Range, X-Upload-Finish")
		h.Set("Access-Control-Max-Age", "600")
		w.WriteHeader(http.StatusNoContent)
		return false
	}
	return true
}
