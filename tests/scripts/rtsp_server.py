#!/usr/bin/env python3
"""An RTSP server on 127.0.0.1 (GStreamer's gst-rtsp-server) serving an H.264 file's stream as
it is, without re-encoding, at the file's own rate. For the network tests.

  rtsp_server.py VIDEO.mp4 [PATH] [--auth USER:PASSWORD]

Prints the port it listens on; the stream is rtsp://127.0.0.1:PORT/stream (or PATH). Each client
gets the file from its start. --auth: only a client with those credentials (RTSP Basic
authentication) may play it; others get 401 Unauthorized.
"""
import sys

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtspServer", "1.0")
from gi.repository import GLib, Gst, GstRtspServer  # noqa: E402


def require_credentials(server, factory, credentials):
    user, password = credentials.split(":", 1)
    token = GstRtspServer.RTSPToken()
    token.set_string(GstRtspServer.RTSP_TOKEN_MEDIA_FACTORY_ROLE, "viewer")
    auth = GstRtspServer.RTSPAuth()
    auth.add_basic(GstRtspServer.RTSPAuth.make_basic(user, password), token)
    server.set_auth(auth)
    permissions = GstRtspServer.RTSPPermissions()
    permissions.add_permission_for_role("viewer", GstRtspServer.RTSP_PERM_MEDIA_FACTORY_ACCESS, True)
    permissions.add_permission_for_role("viewer", GstRtspServer.RTSP_PERM_MEDIA_FACTORY_CONSTRUCT,
                                        True)
    factory.set_permissions(permissions)


def main():
    args = sys.argv[1:]
    credentials = None
    if "--auth" in args:
        at = args.index("--auth")
        credentials = args[at + 1]
        del args[at:at + 2]
    Gst.init(None)
    server = GstRtspServer.RTSPServer.new()
    server.set_address("127.0.0.1")
    server.set_service("0")
    factory = GstRtspServer.RTSPMediaFactory.new()
    location = args[0].replace("\\", "\\\\").replace('"', '\\"')
    factory.set_launch(f'( filesrc location="{location}" ! qtdemux ! h264parse ! '
                       "rtph264pay name=pay0 pt=96 config-interval=-1 )")
    path = args[1] if len(args) > 1 else "/stream"
    if credentials:
        require_credentials(server, factory, credentials)
    server.get_mount_points().add_factory(path, factory)
    if server.attach(None) == 0:
        sys.exit("rtsp_server.py: cannot listen on 127.0.0.1")
    print(server.get_bound_port(), flush=True)
    GLib.MainLoop().run()


if __name__ == "__main__":
    main()
