#!/usr/bin/env python3
"""An RTSP server on 127.0.0.1 (GStreamer's gst-rtsp-server) serving an H.264 file's stream as
it is, without re-encoding, at the file's own rate. For the network tests.

  rtsp_server.py VIDEO.mp4 [PATH]

Prints the port it listens on; the stream is rtsp://127.0.0.1:PORT/stream (or PATH). Each client
gets the file from its start.
"""
import sys

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtspServer", "1.0")
from gi.repository import GLib, Gst, GstRtspServer  # noqa: E402


def main():
    Gst.init(None)
    server = GstRtspServer.RTSPServer.new()
    server.set_address("127.0.0.1")
    server.set_service("0")
    factory = GstRtspServer.RTSPMediaFactory.new()
    location = sys.argv[1].replace("\\", "\\\\").replace('"', '\\"')
    factory.set_launch(f'( filesrc location="{location}" ! qtdemux ! h264parse ! '
                       "rtph264pay name=pay0 pt=96 config-interval=-1 )")
    path = sys.argv[2] if len(sys.argv) > 2 else "/stream"
    server.get_mount_points().add_factory(path, factory)
    if server.attach(None) == 0:
        sys.exit("rtsp_server.py: cannot listen on 127.0.0.1")
    print(server.get_bound_port(), flush=True)
    GLib.MainLoop().run()


if __name__ == "__main__":
    main()
