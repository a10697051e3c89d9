"""``tether view``: one self-contained HTML file replaying a run in 3-D.

Everything the page needs is inside it: three.js r170 (vendored in
``tether/viewing/vendor``, inlined as a classic script), the replay's own scripts
and the run's data (:mod:`tether.viewing.payload`). A Content-Security-Policy of
``default-src 'none'`` forbids the page from fetching anything, so it opens
from ``file://`` offline and cannot call home. Why three.js rather than
plotly: see ``docs/how-to/viewing.md``.
"""

from __future__ import annotations

import contextlib
import hashlib
import html
import http.server
import json
import re
import signal
import threading
import time
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from tether.errors import TetherError
from tether.interrupts import Stopped
from tether.viewing.output import check_target, write_output
from tether.viewing.payload import build_payload
from tether.viewing.runfolder import RunData, load_run

#: A 35-robot run of 10,000 steps must stay under 10 MB; the default aims lower.
DEFAULT_BUDGET_BYTES = 8_000_000
THREE_SHA256 = "08fd7545d13d2c7fb65ab691530a802dafefd638596501854f267d0fb13c39e7"


@dataclass
class Replay:
    path: Path
    bytes: int
    n_frames: int
    stride: int
    seconds: float


def _resource(*parts: str) -> str:
    return resources.files("tether.viewing").joinpath(*parts).read_text(encoding="utf-8")


@lru_cache(maxsize=1)
def three_script() -> str:
    """three.js's one-file module build as a classic script defining the global ``THREE``."""
    src = _resource("vendor", "three.module.min.js")
    digest = hashlib.sha256(src.encode("utf-8")).hexdigest()
    if digest != THREE_SHA256:
        raise TetherError(
            f"tether/viewing/vendor/three.module.min.js: unexpected content ({digest})"
        )
    match = re.search(r"export\s*\{([^}]*)\}\s*;?\s*$", src)
    if match is None:
        raise TetherError("tether/viewing/vendor/three.module.min.js: not a one-file module build")
    names = []
    for item in match.group(1).split(","):
        local, _, exported = item.strip().partition(" as ")
        names.append(f"{(exported or local).strip()}:{local.strip()}")
    body = src[: match.start()]
    return (
        'var THREE=(function(){"use strict";\n' + body + "\nreturn{" + ",".join(names) + "};})();"
    )


def _script_safe(text: str, name: str) -> str:
    """Code that cannot leave the ``<script>`` element it is placed in.

    ``</`` becomes ``<\\/`` (the same in JavaScript); code holding ``<!--`` or ``<script``,
    which switch the HTML parser's script states, is refused (tether's own scripts never do).
    """
    if re.search(r"<!--|<script", text, re.IGNORECASE):
        raise TetherError(f"{name}: holds '<!--' or '<script', which would break the page")
    return text.replace("</", "<\\/")


def script_json(value: Any) -> str:
    """JSON for a ``<script type="application/json">`` element: no ``<``, ``>`` or ``&``.

    Data (a scenario's name, its notes) may hold ``</script>``, ``<!--`` or ``<script``;
    written as ``\\u003c`` and so on, they are the same JSON and cannot end the element or
    switch the HTML parser into a state that swallows the rest of the page.
    """
    text = json.dumps(value, separators=(",", ":"))  # ASCII: U+2028 and U+2029 escaped too
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def render_html(meta: dict[str, Any], blob_b64: str) -> str:
    """The page: template + renderer + replay scripts + data."""
    page = _resource("web", "replay.html")
    if not re.fullmatch(r"[A-Za-z0-9+/=\s]*", blob_b64):
        raise TetherError("replay data: not base64")
    parts = {
        "__TITLE__": html.escape(str(meta.get("name", "run"))),
        "__META__": script_json(meta),
        "__DATA__": blob_b64,
        "__THREE__": _script_safe(three_script(), "three.module.min.js"),
        "__SCENE__": _script_safe(_resource("web", "replay_scene.js"), "replay_scene.js"),
        "__APP__": _script_safe(_resource("web", "replay_app.js"), "replay_app.js"),
    }
    pattern = re.compile("|".join(re.escape(k) for k in parts))
    return pattern.sub(lambda m: parts[m.group(0)], page)


def _fixed_bytes() -> int:
    empty = render_html({}, "")
    return len(empty.encode("utf-8"))


def write_replay(
    run: RunData | str | Path,
    out: str | Path | None = None,
    *,
    budget_bytes: int = DEFAULT_BUDGET_BYTES,
) -> Replay:
    """Write the replay of a run folder (default ``RUN_DIR/replay.html``).

    Long runs are shown every k-th recorded step, the smallest k that keeps the
    file within ``budget_bytes``.
    """
    start = time.perf_counter()
    if out is not None:
        check_target(Path(out))  # before any work
    if not isinstance(run, RunData):
        run = load_run(run)
    if out is None:
        check_target(run.path / "replay.html")
    if run.n_frames == 0:
        raise TetherError(f"{run.path}: nothing to replay (robots.parquet has no rows)")
    fixed = _fixed_bytes()
    if budget_bytes < fixed + 50_000:
        raise TetherError(f"--max-mb: too small; the page alone takes {fixed / 1e6:.2f} MB")
    payload = build_payload(run, budget_bytes=budget_bytes, fixed_bytes=fixed)
    text = render_html(payload.meta, payload.blob_b64)
    out_path = Path(out) if out is not None else run.path / "replay.html"
    data = text.encode("utf-8")
    size = write_output(out_path, lambda tmp: Path(tmp).write_bytes(data), what="replay",
                        run_dir=run.path)  # fmt: skip
    return Replay(
        out_path, size, payload.n_frames_shown, payload.stride, time.perf_counter() - start
    )


class _OneFileHandler(http.server.BaseHTTPRequestHandler):
    """Serves one file at ``/`` (and its own name); everything else is 404."""

    body: bytes = b""
    name: str = "replay.html"

    def do_GET(self) -> None:  # noqa: N802 (http.server's naming)
        if self.path.split("?", 1)[0] not in ("/", f"/{self.name}"):
            self.send_error(404)
            return
        self.send_response(200)
        self.send_header("Content-Type", "text/html; charset=utf-8")
        self.send_header("Content-Length", str(len(self.body)))
        self.end_headers()
        # a browser that leaves mid-reply is its choice, not an error of the server
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            self.wfile.write(self.body)

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
        pass


def bind_server(port: int = 0) -> http.server.ThreadingHTTPServer:
    """An HTTP server bound to 127.0.0.1 (``port`` 0: any free one), serving nothing yet.

    Raises
    ------
    TetherError
        The port is in use or not allowed: one line with the fix.
    """
    handler = type("Handler", (_OneFileHandler,), {"body": b"", "name": "replay.html"})
    try:
        return http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    except OSError as exc:
        raise TetherError(
            f"--port {port}: cannot serve on 127.0.0.1:{port} ({exc.strerror or exc}); choose "
            "another --port, or --port 0 for any free one"
        ) from None


def make_server(
    path: str | Path, port: int = 0, server: http.server.ThreadingHTTPServer | None = None
) -> http.server.ThreadingHTTPServer:
    """An HTTP server for one replay file, bound to 127.0.0.1 only (``port`` 0: any free);
    ``server`` from :func:`bind_server` is used if given (bound before the file was made)."""
    file = Path(path)
    server = bind_server(port) if server is None else server
    server.RequestHandlerClass.body = file.read_bytes()  # type: ignore[attr-defined]
    server.RequestHandlerClass.name = file.name  # type: ignore[attr-defined]
    return server


def serve(
    path: str | Path,
    port: int = 0,
    *,
    announce: Any = print,
    server: http.server.ThreadingHTTPServer | None = None,
) -> None:
    """Serve a replay on 127.0.0.1 until interrupted (Ctrl-C)."""
    server = make_server(path, port, server)
    host, real_port = server.server_address[:2]
    announce(f"serving {path} at http://{host}:{real_port}/ (127.0.0.1 only; Ctrl-C stops)")
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    try:  # Ctrl-C may come as soon as the first request is answered, inside start()
        thread.start()
        while thread.is_alive():
            thread.join(0.5)
    except KeyboardInterrupt:
        pass
    except Stopped as stop:  # Ctrl-C is how serving ends; SIGTERM stops the command
        if stop.signum != signal.SIGINT:
            raise
    finally:
        if thread.is_alive():  # shutdown() waits for a serving loop: only if one runs
            server.shutdown()
        server.server_close()
