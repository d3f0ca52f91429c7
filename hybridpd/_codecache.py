"""An on-disk cache of generated Python source (the SymPy closed forms, for instance).

Generated code is derived once per installation and version, not once per process. Each
entry is one Python file ``NAME-KEY.py`` in :func:`cache_dir`; its first lines record the key
and a SHA-256 checksum of the code below them. :func:`load` executes the cached file when
the key and checksum match, and otherwise regenerates it (missing, stale after an upgrade,
truncated or edited files all count as misses), writing it atomically (temporary file in
the same directory, then ``os.replace``) so that concurrent processes never read half a
file. Old entries of the same name are removed when a new one is written. When no cache
directory is writable the code is generated in memory for this process only.

Location: ``$HYBRIDPD_CACHE_DIR`` if set; else ``$XDG_CACHE_HOME/hybridpd`` or
``~/.cache/hybridpd``; else a ``hybridpd-<user>`` folder in the temporary directory.
Deleting the folder is always safe.
"""
from __future__ import annotations

import hashlib
import os
import re
import tempfile
from pathlib import Path

__all__ = ["cache_dir", "entry_path", "load", "make_key"]

_HEADER = "# hybridpd generated code, do not edit: {name}\n# key: {key}\n# sha256: {digest}\n"
_HEADER_RE = re.compile(r"\A# hybridpd generated code, do not edit: (?P<name>[^\n]*)\n"
                        r"# key: (?P<key>[0-9a-f]+)\n# sha256: (?P<digest>[0-9a-f]+)\n")
_NAME_RE = re.compile(r"\A[A-Za-z0-9_.]+\Z")


class _Miss(Exception):
    """The cached entry is missing, stale or corrupt."""


def _candidates() -> list[Path]:
    env = os.environ.get("HYBRIDPD_CACHE_DIR")
    out = []
    if env:
        out.append(Path(env).expanduser())
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
        out.append(base / "hybridpd")
    try:
        user = str(os.getuid())
    except AttributeError:  # not on POSIX
        user = os.environ.get("USERNAME", "user")
    out.append(Path(tempfile.gettempdir()) / f"hybridpd-{user}")
    return out


def cache_dir() -> Path | None:
    """The first writable cache directory (created if needed), or ``None`` if there is none."""
    for d in _candidates():
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(d, os.W_OK | os.X_OK):
            return d
    return None


def make_key(*parts: str) -> str:
    """Hex key hashing the given strings (versions, source hashes, names)."""
    h = hashlib.sha256()
    for p in parts:
        h.update(str(p).encode())
        h.update(b"\0")
    return h.hexdigest()[:32]


def entry_path(name: str, key: str, directory: Path | None = None) -> Path | None:
    """Path of the entry ``name`` with ``key`` (``None`` without a cache directory)."""
    d = cache_dir() if directory is None else directory
    return None if d is None else d / f"{name}-{key}.py"


def _execute(text: str, name: str, key: str, origin: str) -> dict:
    m = _HEADER_RE.match(text)
    if m is None or m["name"] != name or m["key"] != key:
        raise _Miss("header")
    body = text[m.end():]
    if hashlib.sha256(body.encode()).hexdigest() != m["digest"]:
        raise _Miss("checksum")
    namespace = {"__name__": f"hybridpd._generated.{name}"}
    exec(compile(body, origin, "exec"), namespace)  # noqa: S102 - our own generated code
    return namespace


def _write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}-", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    for old in path.parent.glob(f"{path.name.rsplit('-', 1)[0]}-*.py"):
        if old != path:  # stale entries of the same name
            try:
                old.unlink()
            except OSError:
                pass


def load(name: str, key: str, generate) -> dict:
    """Namespace of the cached code ``name`` with ``key``; ``generate()`` makes the source.

    Parameters
    ----------
    name : str
        Entry name (letters, digits, ``_`` and ``.``).
    key : str
        Hex key (see :func:`make_key`); a different key means the entry is stale.
    generate : callable
        Returns the Python source (a ``str``) to cache; called only on a miss.

    Returns
    -------
    dict
        The globals after executing the code.
    """
    if not _NAME_RE.match(name):
        raise ValueError(f"name must contain only letters, digits, '_' and '.', got {name!r}")
    path = entry_path(name, key)
    if path is not None:
        try:
            return _execute(path.read_text(encoding="utf-8"), name, key, str(path))
        except Exception:  # noqa: BLE001, S110 - a corrupt entry may fail in any way: regenerate
            pass
    body = generate()
    text = _HEADER.format(name=name, key=key,
                          digest=hashlib.sha256(body.encode()).hexdigest()) + body
    namespace = _execute(text, name, key, f"<generated {name}>")
    if path is not None:
        try:
            _write_atomic(path, text)
        except OSError:
            pass  # read-only or full disk: the code still works for this process
    return namespace
