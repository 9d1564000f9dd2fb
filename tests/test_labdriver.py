"""The browser tests' driver (tests/browser/labdriver.py) waits for JupyterLab's answer, not for a
clock: a reply slower than one request's timeout is asked again, never the end of the test."""
import json
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "browser"))
import labdriver  # noqa: E402


class SlowFirstReply(BaseHTTPRequestHandler):
    """/api/sessions: the first request is held until the test lets it go (a busy server), the
    later ones answer at once with one idle kernel."""
    held = threading.Event()
    seen = 0

    def do_GET(self):
        type(self).seen += 1
        if type(self).seen == 1:
            self.held.wait()
        body = json.dumps([{"id": "a", "kernel": {"execution_state": "idle"}}]).encode()
        try:
            self.send_response(200)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)
        except OSError:  # the client stopped listening to the held reply
            pass

    def log_message(self, *args):
        pass


def test_a_reply_slower_than_the_request_timeout_is_asked_again(monkeypatch):
    monkeypatch.setattr(labdriver, "REPLY_TIMEOUT", 0.2)
    server = ThreadingHTTPServer(("127.0.0.1", 0), SlowFirstReply)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}"
    asked = []

    def idle():
        asked.append(1)
        try:
            return "idle" in labdriver.kernel_states(url)
        finally:
            SlowFirstReply.held.set()  # the first request has given up: let its reply go

    try:
        assert labdriver.wait_until(idle, 600, "the kernel to be idle", every=0.01)
        assert len(asked) >= 2 and SlowFirstReply.seen >= 2  # the first ask timed out, a later one answered
    finally:
        SlowFirstReply.held.set()
        server.shutdown()
        server.server_close()
