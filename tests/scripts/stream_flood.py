#!/usr/bin/env python3
"""The stream server under a flood of short connections: connect, `GET /`, close, as fast as one
process can (thousands a second), for FLOOD seconds.

Usage: stream_flood.py LIVEPROBE [FLOOD_SECONDS]

Starts `liveprobe replay synthetic --serve 127.0.0.1:0` with its default limits (256 pending
connections, 32 clients) and, while the flood runs and for 3 s after it, samples the server's open
descriptors every 10 ms and sends a real client every quarter second: GET / (the whole page) and
a WebSocket (the upgrade, then one frame). A thousand connections a second must be made; the
sockets must stay within the pending cap and the clients' (and the few the server holds anyway)
at every sample, and all descriptors within a socket and a file (the page on its way out) for
each of those; every real client must be served, each within WITHIN seconds. A real client waits
behind whatever the kernel's accept queue holds in front of it, so that bound holds only where the
server turns the flood away as fast as it comes.
"""
import multiprocessing
import os
import socket
import sys
import time

sys.dont_write_bytecode = True  # nothing written beside the sources
from stream_clients import (Descriptors, http_get, start_server, stop_server,  # noqa: E402
                            websocket_frame)

LIVEPROBE = sys.argv[1]
FLOOD_SECONDS = float(sys.argv[2]) if len(sys.argv) > 2 else 6.0
PENDING_CAP = 256   # StreamServerOptions::maxPending, the default
CLIENTS = 32        # --serve-clients, the default
MARGIN = 16         # the listening socket, the service loop's own, the process's files
# Seconds a real client may take. The server closes a connection whose peer has hung up as it
# accepts it, so the accept queue stays short: the slowest takes 0.06 s idle and 0.1 to 0.2 s with
# the flood on one of two cores and stress-ng, a renderer and compiles beside. A server that
# answered every flood connection would fall behind the flood and fill the accept queue (4096
# here): 0.7 s idle, 1.3 s beside that load, and seconds more on a busier machine.
WITHIN = 2.0


def flood(port, seconds, count):
    """The flooding process: connect, send GET /, close (without reading), as fast as it can
    until time is up."""
    end = time.monotonic() + seconds
    n = 0
    request = b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
    while time.monotonic() < end:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(request)
            s.close()
            n += 1
        except OSError:
            pass
    with count.get_lock():
        count.value += n


def real_client(port):
    """GET / to the end of the page, then a WebSocket's upgrade and first frame; the seconds it
    took, or None where it was not served."""
    t0 = time.monotonic()
    for _ in range(2):  # a browser retries a connection reset in the flood's first burst
        try:
            if http_get(port) and websocket_frame(port):
                return time.monotonic() - t0
        except OSError:
            pass
    return None


def main():
    server, port = start_server(LIVEPROBE, "--size", "64x36")
    time.sleep(0.5)
    # The listening socket, the process's own files.
    base = len(os.listdir(f"/proc/{server.pid}/fd"))
    count = multiprocessing.Value("i", 0)
    flooders = [multiprocessing.Process(target=flood, args=(port, FLOOD_SECONDS, count))]
    times = []  # (seconds since the flood began, seconds taken or None)
    with Descriptors(server.pid) as descriptors:
        start = time.monotonic()
        for f in flooders:
            f.start()
        while time.monotonic() - start < FLOOD_SECONDS + 3:
            at = time.monotonic() - start
            times.append((at, real_client(port)))
            time.sleep(max(0.0, 0.25 - (time.monotonic() - start - at)))
        for f in flooders:
            f.join()
    samples = descriptors.samples
    err = stop_server(server)
    served = [t for _, t in times if t is not None]
    failed = [at for at, t in times if t is None]
    slow = [(at, t) for at, t in times if t is not None and t > WITHIN]
    most = max(n for _, n, _ in samples)
    sockets = max(k for _, _, k in samples)
    print(f"# {count.value} connections in {FLOOD_SECONDS:.0f} s; descriptors {base} -> at most "
          f"{most}, {sockets} of them sockets ({len(samples)} samples); real clients served "
          f"{len(served)} of {len(times)}, the slowest in {max(served, default=0):.3f} s")
    if count.value < 1000 * FLOOD_SECONDS:
        sys.exit(f"FAIL: only {count.value} connections: no flood")
    # A connection holds its socket, and while the page goes out the page's file too.
    if sockets > PENDING_CAP + CLIENTS + MARGIN:
        sys.exit(f"FAIL: {sockets} sockets open, over the pending cap and the clients")
    if most > base + 2 * (PENDING_CAP + CLIENTS + MARGIN):
        sys.exit(f"FAIL: {most} descriptors open, over a socket and a file per pending connection")
    if failed:
        sys.exit(f"FAIL: real clients not served at {', '.join(f'+{a:.2f} s' for a in failed)}\n{err}")
    if slow:
        sys.exit("FAIL: real clients served late: " +
                 ", ".join(f"{t:.2f} s at +{a:.2f} s" for a, t in slow))
    if server.returncode != 130:
        sys.exit(f"FAIL: exit {server.returncode} after SIGINT\n{err}")
    print("OK")


if __name__ == "__main__":
    main()
