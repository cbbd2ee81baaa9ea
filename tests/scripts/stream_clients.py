"""What the stream's attack tests share: the server started, a real client's two requests, and
the server's descriptors counted while it runs."""
import base64
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time


def start_server(liveprobe, *extra):
    """`liveprobe replay synthetic --serve 127.0.0.1:0` with its default limits; (process, port)."""
    p = subprocess.Popen(
        [liveprobe, "replay", "synthetic:64x32@30", "--headless", "--quiet", *extra,
         "--serve", "127.0.0.1:0"],
        stderr=subprocess.PIPE, text=True)
    line = p.stderr.readline()
    m = re.search(r"serving http://127\.0\.0\.1:(\d+)/", line)
    if not m:
        p.kill()
        sys.exit(f"FAIL: no 'serving' line: {line!r}")
    return p, int(m.group(1))


def http_get(port):
    """GET / to the end of the page: whether it was the page."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
        data = b""
        while b"</html>" not in data.lower():
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    ok = data.startswith(b"HTTP/1.1 200") and b"</html>" in data.lower()
    if not ok:
        print(f"# GET / answered {data[:80]!r}")
    return ok


def websocket_frame(port):
    """The upgrade and the first message (a text frame holding a JSON record)."""
    key = base64.b64encode(os.urandom(16)).decode()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall((f"GET /?format=json HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
                   f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                   f"Sec-WebSocket-Protocol: liveprobe\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                return False
            data += chunk
        head, rest = data.split(b"\r\n\r\n", 1)
        if not head.startswith(b"HTTP/1.1 101"):
            return False
        while len(rest) < 2:
            chunk = s.recv(4096)
            if not chunk:
                return False
            rest += chunk
        return rest[0] == 0x81  # FIN + text


def stop_server(server):
    """SIGINT, then the server's stderr once it has exited (a failure after 10 s)."""
    server.send_signal(signal.SIGINT)
    try:
        _, err = server.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        server.kill()
        sys.exit("FAIL: the server did not stop within 10 s of SIGINT")
    return err


class Descriptors:
    """The server's open descriptors, counted every 10 ms on a thread while the `with` block runs:
    `samples` holds, per count, the seconds since it began, all descriptors, and the sockets."""

    def __init__(self, pid):
        self.fd_dir = f"/proc/{pid}/fd"
        self.samples = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

    def _run(self):
        start = time.monotonic()
        while not self._stop.is_set():
            try:
                links = []
                for fd in os.listdir(self.fd_dir):
                    try:
                        links.append(os.readlink(f"{self.fd_dir}/{fd}"))
                    except OSError:
                        pass  # closed between the listing and the look
                self.samples.append((time.monotonic() - start, len(links),
                                     sum(t.startswith("socket:") for t in links)))
            except OSError:
                pass
            time.sleep(0.01)
