// sheetmesh-gateway: HTTP/JSON in front of the sheetmesh gRPC server, and the web
// front-end. The JSON routes are generated from the protos and
// deploy/gateway/sheetmesh_gateway.yaml; artifact downloads (raw bytes, ranges), resumable
// uploads in chunks, the watch as newline-delimited JSON or Server-Sent Events, the
// OpenAPI document and the front-end are served here.
//
//	sheetmesh-gateway --listen=127.0.0.1:8080 --server=127.0.0.1:50051
//	    [--server_tls --server_ca=ca.pem --server_name=NAME] [--cors_origins=https://a,...]
//	    [--web_root=DIR] [--port_file=FILE]
//
// A request's "Authorization: Bearer <token>" goes through to the server as is; before a
// request's body is read its token is checked, its origin and media type (guard.go). A
// browser opens artifacts through short-lived sealed links, never with a token in a URL
// (links.go).
package main

import (
	"context"
	"errors"
	"flag"
	"fmt"
	"log"
	"net"
	"net/http"
	"net/url"
	"os"
	"os/signal"
	"strings"
	"syscall"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/credentials"
)

// version is set at link time from the project's version (tools/build_gateway.sh).
var version = "unknown"

// errVersion: the command line asked for --version.
var errVersion = errors.New("version")

type options struct {
	listen, server, serverCA, serverName, webRoot, portFile string
	serverTLS                                               bool
	corsOrigins, publicOrigins                              []string
	maxChunkBytes                                           int64
	maxJSONBytes                                            int64
	bodyIdle, bodyGrace                                     time.Duration
	bodyMinRate                                             float64
	linkKeyFile                                             string
	linkTTL                                                 time.Duration
	maxWatchesPerClient                                     int
}

func parseFlags(args []string) (options, error) {
	var o options
	fs := flag.NewFlagSet("sheetmesh-gateway", flag.ContinueOnError)
	fs.StringVar(&o.listen, "listen", "127.0.0.1:8080", "HTTP address to listen on (port 0: any free port)")
	fs.StringVar(&o.server, "server", "127.0.0.1:50051", "the sheetmesh gRPC server, host:port")
	fs.BoolVar(&o.serverTLS, "server_tls", false, "talk TLS to the server")
	fs.StringVar(&o.serverCA, "server_ca", "", "PEM certificates to trust for the server (default: the system's)")
	fs.StringVar(&o.serverName, "server_name", "", "name to expect in the server's certificate (default: its host)")
	cors := fs.String("cors_origins", "", "origins allowed to call from a browser, comma-separated ('*': any)")
	public := fs.String("public_origin", "", "the origins users reach this gateway's own pages at when that is not its --listen address (a DNS name, a proxy), comma-separated")
	fs.StringVar(&o.webRoot, "web_root", "", "serve the front-end from this folder instead of the built-in one")
	fs.StringVar(&o.portFile, "port_file", "", "write the bound port here once listening (for scripts)")
	chunkMB := fs.Int64("max_chunk_mb", 64, "largest upload chunk one request may carry, MiB")
	jsonMB := fs.Int64("max_json_mb", 16, "largest JSON body a request may carry, MiB")
	fs.DurationVar(&o.bodyIdle, "body_idle", 20*time.Second, "a body that brings no byte for this long is cut off")
	fs.DurationVar(&o.bodyGrace, "body_grace", 30*time.Second, "time a body may take before its rate is checked")
	minRateKB := fs.Float64("body_min_kb_per_second", 32, "a body slower than this on average (after --body_grace) is cut off")
	fs.StringVar(&o.linkKeyFile, "link_key_file", "", "32-byte key sealing artifact links (shared by gateways behind one address; default: one made at start)")
	fs.DurationVar(&o.linkTTL, "link_ttl", 10*time.Minute, "how long an artifact link opens its artifact")
	fs.IntVar(&o.maxWatchesPerClient, "max_watches_per_client", 32, "open watches of one client address")
	showVersion := fs.Bool("version", false, "print the version and exit")
	if err := fs.Parse(args); err != nil {
		return o, err
	}
	if *showVersion {
		return o, errVersion
	}
	if fs.NArg() != 0 {
		return o, fmt.Errorf("unexpected argument %q", fs.Arg(0))
	}
	if *chunkMB < 1 || *chunkMB > 4096 {
		return o, fmt.Errorf("--max_chunk_mb=%d: must be within [1, 4096]", *chunkMB)
	}
	o.maxChunkBytes = *chunkMB << 20
	if *jsonMB < 1 || *jsonMB > 1024 {
		return o, fmt.Errorf("--max_json_mb=%d: must be within [1, 1024]", *jsonMB)
	}
	o.maxJSONBytes = *jsonMB << 20
	o.bodyMinRate = *minRateKB * 1024
	if o.bodyIdle <= 0 || o.bodyGrace < 0 || o.bodyMinRate < 0 || o.linkTTL <= 0 || o.maxWatchesPerClient < 1 {
		return o, fmt.Errorf("--body_idle, --link_ttl and --max_watches_per_client must be positive; --body_grace and --body_min_kb_per_second not negative")
	}
	for _, c := range strings.Split(*cors, ",") {
		if c = strings.TrimSpace(c); c != "" {
			o.corsOrigins = append(o.corsOrigins, strings.TrimRight(c, "/"))
		}
	}
	for _, p := range strings.Split(*public, ",") {
		if p = strings.TrimRight(strings.TrimSpace(p), "/"); p != "" {
			if u, err := url.Parse(p); err != nil || (u.Scheme != "http" && u.Scheme != "https") || u.Host == "" || u.Path != "" {
				return o, fmt.Errorf("--public_origin=%s: give scheme://host[:port], e.g. https://sheetmesh.lab.example", p)
			}
			o.publicOrigins = append(o.publicOrigins, p)
		}
	}
	if (o.serverCA != "" || o.serverName != "") && !o.serverTLS {
		return o, fmt.Errorf("--server_ca and --server_name need --server_tls")
	}
	return o, nil
}

func dial(o options) (*grpc.ClientConn, error) {
	creds := grpc.WithInsecure()
	if o.serverTLS {
		if o.serverCA != "" {
			c, err := credentials.NewClientTLSFromFile(o.serverCA, o.serverName)
			if err != nil {
				return nil, fmt.Errorf("--server_ca=%s: %v", o.serverCA, err)
			}
			creds = grpc.WithTransportCredentials(c)
		} else {
			creds = grpc.WithTransportCredentials(credentials.NewClientTLSFromCert(nil, o.serverName))
		}
	}
	// Blob reads come in pieces of at most 1 MiB; job lists can be larger.
	return grpc.Dial(o.server, creds, grpc.WithDefaultCallOptions(grpc.MaxCallRecvMsgSize(64<<20)))
}

func main() {
	log.SetFlags(log.LstdFlags | log.Lmicroseconds)
	o, err := parseFlags(os.Args[1:])
	if err != nil {
		if err == flag.ErrHelp {
			os.Exit(0)
		}
		if err == errVersion {
			fmt.Println("sheetmesh-gateway", version)
			os.Exit(0)
		}
		fmt.Fprintln(os.Stderr, "sheetmesh-gateway:", err)
		os.Exit(2)
	}
	conn, err := dial(o)
	if err != nil {
		fmt.Fprintln(os.Stderr, "sheetmesh-gateway:", err)
		os.Exit(2)
	}
	defer conn.Close()
	ctx, stop := context.WithCancel(context.Background())
	defer stop()
	handler, err := newGateway(ctx, conn, o)
	if err != nil {
		fmt.Fprintln(os.Stderr, "sheetmesh-gateway:", err)
		os.Exit(2)
	}
	ln, err := net.Listen("tcp", o.listen)
	if err != nil {
		fmt.Fprintf(os.Stderr, "sheetmesh-gateway: --listen=%s: %v\n", o.listen, err)
		os.Exit(2)
	}
	handler.self = selfOrigins(ln.Addr(), o.publicOrigins)
	port := ln.Addr().(*net.TCPAddr).Port
	if o.portFile != "" {
		tmp := o.portFile + ".tmp"
		if err := os.WriteFile(tmp, []byte(fmt.Sprintf("%d\n", port)), 0o644); err == nil {
			err = os.Rename(tmp, o.portFile)
		}
		if err != nil {
			fmt.Fprintf(os.Stderr, "sheetmesh-gateway: --port_file=%s: %v\n", o.portFile, err)
			os.Exit(2)
		}
	}
	srv := &http.Server{Handler: handler, ReadHeaderTimeout: 30 * time.Second, ConnContext: withConn}
	done := make(chan struct{})
	go func() {
		sig := make(chan os.Signal, 1)
		signal.Notify(sig, syscall.SIGINT, syscall.SIGTERM)
		<-sig
		stop() // ends the watches
		c, cancel := context.WithTimeout(context.Background(), 10*time.Second)
		defer cancel()
		srv.Shutdown(c)
		close(done)
	}()
	log.Printf("sheetmesh-gateway: listening on %s, server %s", ln.Addr(), o.server)
	if err := srv.Serve(ln); err != http.ErrServerClosed {
		fmt.Fprintln(os.Stderr, "sheetmesh-gateway:", err)
		os.Exit(1)
	}
	<-done
}
