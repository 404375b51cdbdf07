package main

import (
	"crypto/aes"
	"crypto/cipher"
	"crypto/rand"
	"encoding/base64"
	"encoding/json"
	"fmt"
	"net/http"
	"net/url"
	"os"
	"strings"
	"time"

	"google.golang.org/grpc/codes"
	pb "sheetmesh/v1"
)

// Links to one artifact that a browser can open without headers (an <img>, a download):
// POST /v1/jobs/{id}/artifacts/{name}:link, with the caller's token in its header, answers
// a URL whose `link` parameter seals that token, the job, the name and an expiry with
// AES-GCM under the gateway's key. The token never appears in a URL, and a link opens one
// artifact for a few minutes only. Gateways behind one address share the key file
// (--link_key_file); without one, each makes its own at start.

type linkSealer struct {
	aead cipher.AEAD
	ttl  time.Duration
}

type sealedLink struct {
	Auth    string `json:"a"`
	Job     string `json:"j"`
	Name    string `json:"n"`
	Expires int64  `json:"e"`
}

// newLinkSealer reads a 32-byte key from keyFile (raw or 64 hex digits), or makes one.
func newLinkSealer(keyFile string, ttl time.Duration) (*linkSealer, error) {
	key := make([]byte, 32)
	if keyFile == "" {
		if _, err := rand.Read(key); err != nil {
			return nil, err
		}
	} else {
		raw, err := os.ReadFile(keyFile)
		if err != nil {
			return nil, fmt.Errorf("--link_key_file=%s: %v", keyFile, err)
		}
		text := strings.TrimSpace(string(raw))
		if len(text) == 64 {
			if _, err := fmt.Sscanf(text, "%x", &key); err != nil {
				return nil, fmt.Errorf("--link_key_file=%s: not 64 hex digits", keyFile)
			}
		} else if len(raw) == 32 {
			key = raw
		} else {
			return nil, fmt.Errorf("--link_key_file=%s: holds %d bytes; it needs 32 bytes or 64 hex digits",
				keyFile, len(raw))
		}
	}
	block, err := aes.NewCipher(key)
	if err != nil {
		return nil, err
	}
	aead, err := cipher.NewGCM(block)
	if err != nil {
		return nil, err
	}
	return &linkSealer{aead: aead, ttl: ttl}, nil
}

func (s *linkSealer) seal(l sealedLink) (string, error) {
	plain, err := json.Marshal(l)
	if err != nil {
		return "", err
	}
	nonce := make([]byte, s.aead.NonceSize())
	if _, err := rand.Read(nonce); err != nil {
		return "", err
	}
	return base64.RawURLEncoding.EncodeToString(s.aead.Seal(nonce, nonce, plain, nil)), nil
}

// open returns the link's contents, or why it may not be used for job/name now.
func (s *linkSealer) open(text, job, name string, now time.Time) (sealedLink, error) {
	var l sealedLink
	raw, err := base64.RawURLEncoding.DecodeString(text)
	n := s.aead.NonceSize()
	if err != nil || len(raw) < n {
		return l, fmt.Errorf("the link is malformed")
	}
	plain, err := s.aead.Open(nil, raw[:n], raw[n:], nil)
	if err != nil || json.Unmarshal(plain, &l) != nil {
		return l, fmt.Errorf("the link was not made by this gateway (or its key changed)")
	}
	if l.Job != job || l.Name != name {
		return l, fmt.Errorf("the link is for %s/artifacts/%s", l.Job, l.Name)
	}
	if now.Unix() > l.Expires {
		return l, fmt.Errorf("the link expired at %s", time.Unix(l.Expires, 0).UTC().Format(time.RFC3339))
	}
	return l, nil
}

// makeLink answers POST .../artifacts/{name}:link: the artifact must exist for the caller.
func (g *gateway) makeLink(w http.ResponseWriter, r *http.Request, job, name string) {
	j, err := g.jobs.GetJob(outgoing(r), &pb.GetJobRequest{Name: job})
	if err != nil {
		writeError(w, err)
		return
	}
	found := false
	for _, a := range j.Artifacts {
		found = found || a.Name == name
	}
	if !found {
		writeErrorCode(w, codes.NotFound, fmt.Sprintf("%s has no artifact %q", job, name))
		return
	}
	expires := time.Now().Add(g.links.ttl)
	sealed, err := g.links.seal(sealedLink{Auth: r.Header.Get("Authorization"), Job: job,
		Name: name, Expires: expires.Unix()})
	if err != nil {
		writeErrorCode(w, codes.Internal, "sealing the link: "+err.Error())
		return
	}
	writeJSONStatus(w, http.StatusOK, map[string]interface{}{
		"url":         fmt.Sprintf("/v1/%s/artifacts/%s?link=%s", job, url.PathEscape(name), sealed),
		"expire_time": expires.UTC().Format(time.RFC3339)})
}

// fromLink makes a request carrying ?link= one with the link's token; false (answered)
// when the link may not be used.
func (g *gateway) fromLink(w http.ResponseWriter, r *http.Request, job, name string) bool {
	text := r.URL.Query().Get("link")
	if text == "" {
		return true
	}
	l, err := g.links.open(text, job, name, time.Now())
	if err != nil {
		writeErrorCode(w, codes.PermissionDenied, err.Error()+": ask for a new one (POST "+
			r.URL.Path+":link)")
		return false
	}
	if l.Auth != "" {
		r.Header.Set("Authorization", l.Auth)
	}
	return true
}
