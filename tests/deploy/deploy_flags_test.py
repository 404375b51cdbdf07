#!/usr/bin/python3
"""Every command in deploy/compose.yaml and deploy/k8s/*.yaml names a binary the image
ships and only flags that binary has (as its --help lists them), so a renamed flag cannot
leave a manifest behind.

    /usr/bin/python3 tests/deploy/deploy_flags_test.py ROOT BUILD_DIR
"""
import os
import re
import subprocess
import sys

import yaml

BINARIES = {"sheetmesh-server": "server/sheetmesh-server", "sheetmesh-worker": "worker/remote/sheetmesh-worker",
            "sheetmesh-gateway": "gateway/sheetmesh-gateway", "sheetmesh": "client/sheetmesh",
            "sheetmesh-pipeline": "worker/pipeline/sheetmesh-pipeline"}


def commands(doc):
    """The command lines of a compose file or a Kubernetes object."""
    if isinstance(doc, dict) and "services" in doc:
        for name, svc in doc["services"].items():
            if isinstance(svc.get("command"), list):
                yield "compose service %s" % name, svc["command"]
        return
    spec = (doc or {}).get("spec", {}).get("template", {}).get("spec", {})
    for c in spec.get("containers", []):
        if c.get("args"):
            yield "%s %s container %s" % (doc["kind"], doc["metadata"]["name"], c["name"]), c["args"]


def flags_of(path, cache={}):
    if path not in cache:
        out = subprocess.run([path, "--help"], capture_output=True, text=True, timeout=30)
        cache[path] = set(re.findall(r"--?([a-z_][a-z0-9_]*)", out.stdout + out.stderr))
    return cache[path]


def main(root, build):
    files = [os.path.join(root, "deploy/compose.yaml")] + [
        os.path.join(root, "deploy/k8s", f) for f in sorted(os.listdir(os.path.join(root, "deploy/k8s")))]
    errors, checked = [], 0
    for f in files:
        for doc in yaml.safe_load_all(open(f)):
            for where, argv in commands(doc):
                binary = argv[0]
                if binary not in BINARIES:
                    errors.append("%s: %s: %r is not a binary the image ships" % (f, where, binary))
                    continue
                path = os.path.join(build, BINARIES[binary])
                if not os.path.exists(path):
                    print("SKIP %s: %s not built" % (where, path))
                    continue
                known = flags_of(path)
                for a in argv[1:]:
                    if a.startswith("--"):
                        flag = a[2:].split("=", 1)[0]
                        checked += 1
                        if flag not in known:
                            errors.append("%s: %s: %s has no flag --%s" % (f, where, binary, flag))
    for e in errors:
        print("FAIL", e)
    print("%d flags checked in %d files" % (checked, len(files)))
    return 1 if errors or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
