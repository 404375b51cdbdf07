package main

import (
	"bytes"
	"encoding/json"
	"fmt"
	"io"
	"strings"

	"github.com/golang/protobuf/jsonpb"
	"github.com/golang/protobuf/proto"
	"github.com/grpc-ecosystem/grpc-gateway/runtime"
)

// strictJSON is the JSON of the protos with their field names as the protos spell them
// (the names the server's messages use), every field written, and unknown fields in a
// request refused rather than dropped.
type strictJSON struct{}

var jsonOut = jsonpb.Marshaler{OrigName: true, EmitDefaults: true}

func (strictJSON) ContentType() string { return "application/json" }

func (strictJSON) Marshal(v interface{}) ([]byte, error) {
	if m, ok := v.(proto.Message); ok {
		var b bytes.Buffer
		if err := jsonOut.Marshal(&b, m); err != nil {
			return nil, err
		}
		return b.Bytes(), nil
	}
	return json.Marshal(v)
}

func (strictJSON) Unmarshal(data []byte, v interface{}) error {
	return decodeStrict(json.NewDecoder(bytes.NewReader(data)), v)
}

func (strictJSON) NewDecoder(r io.Reader) runtime.Decoder {
	d := json.NewDecoder(r)
	return runtime.DecoderFunc(func(v interface{}) error { return decodeStrict(d, v) })
}

func (s strictJSON) NewEncoder(w io.Writer) runtime.Encoder {
	return runtime.EncoderFunc(func(v interface{}) error {
		b, err := s.Marshal(v)
		if err != nil {
			return err
		}
		_, err = w.Write(b)
		return err
	})
}

func (strictJSON) Delimiter() []byte { return []byte("\n") }

func decodeStrict(d *json.Decoder, v interface{}) error {
	m, ok := v.(proto.Message)
	if !ok {
		// Path and query fields of scalar type come here as plain JSON.
		return d.Decode(v)
	}
	u := jsonpb.Unmarshaler{AllowUnknownFields: false}
	if err := u.UnmarshalNext(d, m); err != nil {
		if err == io.EOF {
			return err // the end of a stream of requests, not an error
		}
		// Name the message as the protos do, not as its Go package does.
		return fmt.Errorf("request body: %s", strings.ReplaceAll(err.Error(), "sheetmeshv1.", "sheetmesh.v1."))
	}
	return nil
}
