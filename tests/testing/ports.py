"""Waiting for a process started by a test to say which port it took."""

import time


def wait_port_file(path, proc, what, timeout=60, log=None):
    """The port a process writes to `path` (a line ending in a newline) once serving. Raises,
    with the log's text when given, if it exits or says nothing within `timeout` seconds."""
    deadline = time.time() + timeout
    while not (path.exists() and path.read_text().endswith("\n")):
        if time.time() > deadline or proc.poll() is not None:
            detail = log.read_text() if log is not None and log.exists() else ""
            raise RuntimeError("%s did not start %s" % (what, detail))
        time.sleep(0.02)
    return int(path.read_text())
