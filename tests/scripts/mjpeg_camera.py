#!/usr/bin/env python3
"""A motion-JPEG camera on 127.0.0.1, as an ESP32 camera or a phone app serves one: HTTP
multipart/x-mixed-replace, one JPEG per part, at a steady rate. For the network tests.

  mjpeg_camera.py JPEG [--fps 30] [--drop-after N] [--down SECONDS] [--auth USER:PASS]
                  [--silent-after N] [--tls CERT.pem,KEY.pem]

Prints the port it listens on, then serves every client the JPEG over and over. --drop-after N
closes a connection after N frames and refuses new ones (the port closed) for --down seconds,
as a camera on a Wi-Fi link that goes away; --silent-after N keeps the connection open but sends
nothing more after N frames (a stall). --auth asks for HTTP Basic credentials. --tls serves
HTTPS with that certificate and key.
"""
import argparse
import base64
import socket
import ssl
import sys
import threading
import time

BOUNDARY = b"liveprobeframe"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("jpeg")
    ap.add_argument("--fps", type=float, default=30)
    ap.add_argument("--drop-after", type=int, default=0)
    ap.add_argument("--down", type=float, default=0)
    ap.add_argument("--silent-after", type=int, default=0)
    ap.add_argument("--auth", default="")
    ap.add_argument("--tls", default="")
    a = ap.parse_args()
    tls = None
    if a.tls:
        tls = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        tls.load_cert_chain(*a.tls.split(","))
    with open(a.jpeg, "rb") as f:
        jpeg = f.read()
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    listener.listen(8)
    print(port, flush=True)
    state = {"listener": listener}
    down_until = [0.0]

    def serve(conn):
        try:
            if tls:
                conn = tls.wrap_socket(conn, server_side=True)
            request = b""
            while b"\r\n\r\n" not in request:
                chunk = conn.recv(4096)
                if not chunk:
                    return
                request += chunk
            if a.auth:
                want = b"Basic " + base64.b64encode(a.auth.encode())
                if b"authorization: " + want.lower() not in request.lower():
                    conn.sendall(b"HTTP/1.1 401 Unauthorized\r\nWWW-Authenticate: Basic "
                                 b"realm=\"camera\"\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")
                    return
            conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: multipart/x-mixed-replace; boundary="
                         + BOUNDARY + b"\r\nCache-Control: no-cache\r\nConnection: close\r\n\r\n")
            sent = 0
            start = time.monotonic()
            while True:
                if a.silent_after and sent >= a.silent_after:
                    time.sleep(3600)
                conn.sendall(b"--" + BOUNDARY + b"\r\nContent-Type: image/jpeg\r\nContent-Length: "
                             + str(len(jpeg)).encode() + b"\r\n\r\n" + jpeg + b"\r\n")
                sent += 1
                if a.drop_after and sent >= a.drop_after:
                    # The camera goes away: the connection dropped, the port closed for a while.
                    down_until[0] = time.monotonic() + a.down
                    try:
                        state["listener"].shutdown(socket.SHUT_RDWR)  # wakes the accept()
                    except OSError:
                        pass
                    state["listener"].close()
                    return
                delay = start + sent / a.fps - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
        except OSError:
            pass
        finally:
            conn.close()

    while True:
        try:
            conn, _ = state["listener"].accept()
        except OSError:
            # Closed by a drop: refuse connections until the camera is back, then listen again.
            time.sleep(max(0.0, down_until[0] - time.monotonic()))
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind(("127.0.0.1", port))
            s.listen(8)
            state["listener"] = s
            continue
        threading.Thread(target=serve, args=(conn,), daemon=True).start()


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(0)
