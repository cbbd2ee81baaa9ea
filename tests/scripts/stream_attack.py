#!/usr/bin/env python3
"""The stream server under a slowloris: real clients are served while silent sockets are held.

Usage: stream_attack.py LIVEPROBE [SILENT] [ATTACKER]

Starts `liveprobe replay synthetic --serve 127.0.0.1:0` with its default limits, opens SILENT
(default 200) TCP connections from ATTACKER (127.0.0.2) that send nothing, or one byte of a request
line a second, and reopens every one the server closes. Meanwhile a real client every half second
asks for the page (GET /) and opens a WebSocket (the upgrade, then one frame). Every real client
must be served, while the attack holds; the server must close the silent sockets (a handshake
deadline, and the bound on one address's pending connections: over it the oldest silent one is
closed, so the attacker's sockets in the server stay near that bound), and answer at exit with
its summary. A bystander's few silent sockets from a third address, opened just before the
attack, are another address's: the attack must not close them before their own deadline.
"""
import select
import socket
import sys
import time

sys.dont_write_bytecode = True  # nothing written beside the sources
from stream_clients import (Descriptors, http_get, start_server, stop_server,  # noqa: E402
                            websocket_frame)

LIVEPROBE = sys.argv[1]
SILENT = int(sys.argv[2]) if len(sys.argv) > 2 else 200
ATTACK_SECONDS = 14
ATTACKER = sys.argv[3] if len(sys.argv) > 3 else "127.0.0.2"
PER_ADDRESS = 64  # StreamServerOptions::maxPendingPerAddress, the default
CLIENTS = 32      # --serve-clients, the default
MARGIN = 16       # the listening socket, the service loop's own, the process's files
BYSTANDER = "127.0.0.3"
BYSTANDERS = 16   # under one address's bound
DEADLINE = 3.0    # --serve's handshake deadline, seconds


def main():
    server, port = start_server(LIVEPROBE)
    silent = []

    def open_silent(address=ATTACKER):
        s = socket.socket()
        s.bind((address, 0))
        s.setblocking(False)
        s.connect_ex(("127.0.0.1", port))
        return [s, time.monotonic()]

    bystanders = [open_silent(BYSTANDER) for _ in range(BYSTANDERS)]
    time.sleep(0.2)  # accepted before the attack
    for _ in range(SILENT):
        silent.append(open_silent())
    served = failed = reopened = 0
    bystanders_closed = []  # seconds after it was opened
    with Descriptors(server.pid) as descriptors:
        start = time.monotonic()
        next_real = start + 1.0
        while time.monotonic() - start < ATTACK_SECONDS:
            # Slow drip: one byte of a request line from every tenth socket, once a second.
            now = time.monotonic()
            for i, entry in enumerate(silent):
                s, last = entry
                if i % 10 == 0 and now - last >= 1.0:
                    try:
                        s.send(b"G")
                    except OSError:
                        pass
                    entry[1] = now
            # A bystander closed before its deadline was closed for another address's sockets.
            for entry in list(bystanders):
                s, opened = entry
                if select.select([s], [], [], 0)[0]:
                    bystanders_closed.append(time.monotonic() - opened)
                    bystanders.remove(entry)
                    s.close()
            # Reopen what the server closed.
            readable, _, _ = select.select([e[0] for e in silent], [], [], 0.05)
            for s in readable:
                try:
                    closed = s.recv(1) == b""
                except OSError:
                    closed = True
                if closed:
                    i = next(k for k, e in enumerate(silent) if e[0] is s)
                    s.close()
                    silent[i] = open_silent()
                    reopened += 1
            if time.monotonic() >= next_real:
                next_real += 0.5
                t0 = time.monotonic()
                try:
                    ok = http_get(port)
                    if not ok:
                        print("# real client: GET / was not answered with the page")
                    elif not websocket_frame(port):
                        ok = False
                        print("# real client: the WebSocket was not upgraded, or sent no frame")
                except OSError as e:
                    print(f"# real client: {e!r} after {time.monotonic() - t0:.2f} s")
                    ok = False
                served += ok
                failed += not ok
    for s, _ in silent + bystanders:
        s.close()
    err = stop_server(server)
    # lws accepts what waits in the kernel's queue in one go, and a connection told to close
    # goes at its next turn of the service loop: at a moment the server may hold all of the
    # attacker's sockets, so the bound is on the median.
    sockets = sorted(k for _, _, k in descriptors.samples)
    held = sockets[len(sockets) // 2]
    print(f"# {SILENT} silent sockets held for {ATTACK_SECONDS} s, {reopened} reopened after the "
          f"server closed them; real clients served {served}, failed {failed}; the server held "
          f"{held} sockets (median; at most {sockets[-1]})")
    if failed or served < 2 * (ATTACK_SECONDS - 2):
        sys.exit(f"FAIL: real clients were not served throughout\n{err}")
    if reopened < SILENT:
        sys.exit("FAIL: the silent sockets were not closed by the handshake deadline")
    early = [t for t in bystanders_closed if t < DEADLINE - 0.5]
    if early:
        sys.exit(f"FAIL: {len(early)} of the bystander's {BYSTANDERS} sockets closed before their "
                 f"deadline, at {min(early):.2f} s: one address's bound closed another's")
    if held > PER_ADDRESS + CLIENTS + MARGIN:
        sys.exit(f"FAIL: the server held {held} sockets, over one address's pending bound")
    if server.returncode != 130:
        sys.exit(f"FAIL: exit {server.returncode} after SIGINT\n{err}")
    print("OK")


main()
