"""Serving the explorer: one page per browser session on a local address."""
from __future__ import annotations

import socket

from hybridpd.model import check_int

__all__ = ["free_port", "serve"]


def free_port(address: str = "127.0.0.1") -> int:
    """A TCP port free on ``address`` now (the system's choice)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((address, 0))
        return int(s.getsockname()[1])


def serve(port: int = 0, *, address: str = "127.0.0.1", open_browser: bool = True,
          app=None, threaded: bool = False, verbose: bool = True):
    """Serve the explorer at ``http://ADDRESS:PORT/`` (each session builds its own page).

    Parameters
    ----------
    port : int
        TCP port, 0 for a free one chosen now.
    address : str
        Where to listen; the default keeps the page on this machine.
    open_browser : bool
        Open the page in the default web browser.
    app : callable, optional
        Builds one session's page (default: the impact pair's,
        :func:`hybridpd.explore.app.pair_app`).
    threaded : bool
        Serve on a thread and return it (``.stop()`` ends it); else block until interrupted.
    verbose : bool
        Print the address.

    Returns
    -------
    The server thread (``threaded``), else the stopped server.
    """
    port = check_int("port", port, 0, 65535)
    if port == 0:
        port = free_port(address)
    # deferred import: panel and the page load only when a server starts
    import panel as pn

    if app is None:
        # deferred import: panel and the page load only when a server starts
        from hybridpd.explore.app import pair_app as app
    origins = [f"{address}:{port}", f"localhost:{port}"]
    kw = dict(port=port, address=address, show=open_browser, websocket_origin=origins,
              verbose=False, title="hybridpd explore")
    if threaded:
        thread = pn.serve({"/": app}, threaded=True, **kw)
        _wait_listening(address, port)
        _say(verbose, address, port)
        return thread
    server = pn.serve({"/": app}, start=False, **kw)    # bound and listening from here
    _say(verbose, address, port)
    server.start()
    try:
        server.io_loop.start()
    except KeyboardInterrupt:
        pass
    return server


def _say(verbose: bool, address: str, port: int):
    if verbose:
        print(f"hybridpd explore: serving http://{address}:{port}/ (Ctrl-C stops)",
              flush=True)


def _wait_listening(address: str, port: int, timeout: float = 30.0):
    """Return once ``address:port`` accepts connections (``TimeoutError`` after
    ``timeout`` seconds)."""
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:          # bounded by the deadline
        try:
            with socket.create_connection((address, port), timeout=1.0):
                return
        except OSError:
            time.sleep(0.02)
    raise TimeoutError(f"the explorer's server did not listen on {address}:{port} within "
                       f"{timeout:g} s")
