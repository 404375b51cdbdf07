#!/usr/bin/python3
"""Checks deploy/gateway/sheetmesh_gateway.yaml against the protos: every RPC has exactly
one HTTP rule, every selector names a real method, every path variable names a field of
the request (following dotted paths through messages), GET/DELETE carry no body, and no
two rules share a verb and path template.

    /usr/bin/python3 tests/deploy/gateway_test.py PROTOC PROTO_DIR GATEWAY_YAML
"""

import re
import subprocess
import sys
import tempfile

import yaml
from google.protobuf import descriptor_pb2

VERBS = ("get", "post", "put", "patch", "delete")


def main(protoc, proto_dir, gateway):
    with tempfile.NamedTemporaryFile(suffix=".pb") as out:
        protos = ["sheetmesh/v1/%s.proto" % p for p in ("common", "blobs", "jobs", "parameters", "volumes")]
        subprocess.run([protoc, "--proto_path=" + proto_dir, "--include_imports",
                        "--descriptor_set_out=" + out.name] + protos, check=True)
        fds = descriptor_pb2.FileDescriptorSet.FromString(open(out.name, "rb").read())
    messages, methods = {}, {}
    for f in fds.file:
        for m in f.message_type:
            messages["%s.%s" % (f.package, m.name)] = m
        for s in f.service:
            for m in s.method:
                methods["%s.%s.%s" % (f.package, s.name, m.name)] = m
    config = yaml.safe_load(open(gateway))
    errors = []
    if config.get("type") != "google.api.Service":
        errors.append("type must be google.api.Service")
    seen, templates = set(), set()
    for rule in config["http"]["rules"]:
        sel = rule["selector"]
        if sel not in methods:
            errors.append("%s: no such method" % sel)
            continue
        if sel in seen:
            errors.append("%s: more than one rule" % sel)
        seen.add(sel)
        verbs = [v for v in VERBS if v in rule]
        if len(verbs) != 1:
            errors.append("%s: needs exactly one HTTP verb" % sel)
            continue
        verb, path = verbs[0], rule[verbs[0]]
        if (verb, path) in templates:
            errors.append("%s: %s %s is used twice" % (sel, verb, path))
        templates.add((verb, path))
        if verb in ("get", "delete") and "body" in rule:
            errors.append("%s: %s takes no body" % (sel, verb))
        request = messages[methods[sel].input_type.lstrip(".")]
        for var in re.findall(r"\{([^}=]+)(?:=[^}]*)?\}", path):
            msg = request
            for i, part in enumerate(var.split(".")):
                field = next((f for f in msg.field if f.name == part), None)
                if field is None:
                    errors.append("%s: path variable %s: %s has no field %s" % (sel, var, msg.name, part))
                    break
                if i < len(var.split(".")) - 1:
                    if field.type != descriptor_pb2.FieldDescriptorProto.TYPE_MESSAGE:
                        errors.append("%s: path variable %s: %s is not a message" % (sel, var, part))
                        break
                    msg = messages[field.type_name.lstrip(".")]
    for m in methods:
        if m.startswith("sheetmesh.") and m not in seen:
            errors.append("%s has no HTTP rule" % m)
    for e in errors:
        print("FAIL: " + e)
    print("%d rules, %d methods, %d problems" % (len(seen), len(methods), len(errors)))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
