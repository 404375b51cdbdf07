package main

import (
	"embed"
	"encoding/json"
	"fmt"
	"io/fs"
	"net/http"
	"os"
	"path"
	"strings"
)

// The front-end (web/dist, built by npm) and the OpenAPI document (generated from the
// protos), copied next to these sources by tools/build_gateway.sh.
//
//go:embed all:webdist
var webFiles embed.FS

//go:embed sheetmesh.swagger.json
var generatedOpenAPI []byte

//go:embed openapi_extra.json
var extraOpenAPI []byte

func webHandler(root string) (http.Handler, error) {
	var files fs.FS
	if root != "" {
		if st, err := os.Stat(path.Join(root, "index.html")); err != nil || st.IsDir() {
			return nil, fmt.Errorf("--web_root=%s: no index.html there", root)
		}
		files = os.DirFS(root)
	} else {
		sub, err := fs.Sub(webFiles, "webdist")
		if err != nil {
			return nil, err
		}
		files = sub
	}
	static := http.FileServer(http.FS(files))
	return http.HandlerFunc(func(w http.ResponseWriter, r *http.Request) {
		if r.Method != http.MethodGet && r.Method != http.MethodHead {
			onlyMethods(w, r, http.MethodGet, http.MethodHead)
			return
		}
		p := strings.TrimPrefix(path.Clean(r.URL.Path), "/")
		if p == "" {
			p = "index.html"
		}
		if _, err := fs.Stat(files, p); err != nil {
			// The front-end's own routes (#/jobs/...) all load index.html.
			r.URL.Path = "/"
		}
		if strings.HasPrefix(p, "assets/") {
			w.Header().Set("Cache-Control", "public, max-age=31536000, immutable")
		} else {
			w.Header().Set("Cache-Control", "no-cache")
		}
		static.ServeHTTP(w, r)
	}), nil
}

// openAPIDocument merges the generated document with the routes written by hand here.
func openAPIDocument() ([]byte, error) {
	var doc, extra map[string]interface{}
	if err := json.Unmarshal(generatedOpenAPI, &doc); err != nil {
		return nil, fmt.Errorf("sheetmesh.swagger.json: %v", err)
	}
	if err := json.Unmarshal(extraOpenAPI, &extra); err != nil {
		return nil, fmt.Errorf("openapi_extra.json: %v", err)
	}
	paths, _ := doc["paths"].(map[string]interface{})
	if paths == nil {
		paths = map[string]interface{}{}
	}
	for k, v := range extra["paths"].(map[string]interface{}) {
		paths[k] = v
	}
	doc["paths"] = paths
	doc["info"] = extra["info"]
	return json.MarshalIndent(doc, "", "  ")
}
