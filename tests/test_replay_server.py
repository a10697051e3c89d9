"""The replay server of ``tether view --serve`` shrugs off a browser that leaves mid-reply."""

from __future__ import annotations

import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from tether.viewing.replay import make_server


def test_a_client_that_leaves_mid_reply_prints_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    page = tmp_path / "replay.html"
    page.write_bytes(b"x" * 32_000_000)  # far more than the socket buffers hold
    server = make_server(page)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        host, port = server.server_address[:2]
        for _ in range(3):
            with socket.create_connection((host, port)) as client:
                client.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
                client.recv(1024)  # the reply has started
                # close with a reset, as a browser tab that is closed
                client.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        time.sleep(0.5)  # the handler threads meet the closed connections
    finally:
        server.shutdown()
        server.server_close()
    err = capsys.readouterr().err
    assert "Traceback" not in err and "Exception occurred" not in err, err[-2000:]
