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
``~/.cache/hybridpd``; if that cannot be created or written, a ``hybridpd-<uid>`` folder in
the temporary directory. Deleting the folder is always safe.

Safety: the checksum only detects damage, not tampering, since it is written in the same
file. So, as ssh and pip do, the cache is trusted only if nobody else can write it: the
directory and every entry must be owned by the current user and not writable by group or
others (entries are opened without following symbolic links and checked on the open file).
A directory is created with mode ``0700``; a temporary-directory folder that already exists
must be a real directory owned by the user with no permissions for group or others. When a
check fails the cache is not used: the code is generated in memory and a one-line
:class:`UnsafeCacheWarning` says why. On systems without POSIX owners (Windows) the checks
are skipped.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import stat
import tempfile
import warnings
from pathlib import Path

__all__ = ["UnsafeCacheWarning", "cache_dir", "entry_path", "load", "make_key"]

_HEADER = "# hybridpd generated code, do not edit: {name}\n# key: {key}\n# sha256: {digest}\n"
_HEADER_RE = re.compile(r"\A# hybridpd generated code, do not edit: (?P<name>[^\n]*)\n"
                        r"# key: (?P<key>[0-9a-f]+)\n# sha256: (?P<digest>[0-9a-f]+)\n")
_NAME_RE = re.compile(r"\A[A-Za-z0-9_.]+\Z")
_POSIX = hasattr(os, "getuid")


class UnsafeCacheWarning(UserWarning):
    """The code cache (or one entry) could be written by someone else and is not used."""


class _Miss(Exception):
    """The cached entry is missing, stale or corrupt."""


class _Unsafe(Exception):
    """The cache directory or an entry is not safe to execute from; the message says why."""


def _preferred() -> Path:
    env = os.environ.get("HYBRIDPD_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "hybridpd"


def _fallback() -> Path:
    user = str(os.getuid()) if _POSIX else os.environ.get("USERNAME", "user")
    return Path(tempfile.gettempdir()) / f"hybridpd-{user}"


def _check_owner(st: os.stat_result, what: str, forbidden: int) -> None:
    """Raise :class:`_Unsafe` unless ``st`` is owned by us and has none of ``forbidden``."""
    if not _POSIX:
        return
    if st.st_uid != os.getuid():
        raise _Unsafe(f"{what} is owned by uid {st.st_uid}, not by the current user "
                      f"(uid {os.getuid()})")
    if st.st_mode & forbidden:
        mode = f"{stat.S_IMODE(st.st_mode):04o}"
        if forbidden == 0o022:
            raise _Unsafe(f"{what} is writable by group or others (mode {mode})")
        raise _Unsafe(f"{what} already exists with mode {mode}, not 0700")


def _usable(d: Path, forbidden: int) -> bool:
    """Whether the existing directory ``d`` is safe; raise :class:`_Unsafe` if it is not."""
    st = os.lstat(d) if forbidden == 0o077 else os.stat(d)
    if stat.S_ISLNK(st.st_mode):
        raise _Unsafe(f"{d} is a symbolic link")
    if not stat.S_ISDIR(st.st_mode):
        raise _Unsafe(f"{d} is not a directory")
    _check_owner(st, str(d), forbidden)
    return os.access(d, os.W_OK | os.X_OK)


def _locate() -> tuple[Path | None, str | None]:
    """The cache directory, or ``None`` and why none is used (``None`` if merely unwritable)."""
    d = _preferred()
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
        if _usable(d, 0o022):
            return d, None
    except _Unsafe as exc:
        return None, str(exc)
    except OSError:
        pass  # cannot be created (read-only home, a file in the way): try the fallback
    d = _fallback()
    try:
        with contextlib.suppress(FileExistsError):
            os.mkdir(d, 0o700)
        # someone else may have created it first: it must be ours and closed to everybody else
        if _usable(d, 0o077):
            return d, None
    except _Unsafe as exc:
        return None, str(exc)
    except OSError:
        pass
    return None, None


def cache_dir() -> Path | None:
    """The cache directory (created if needed), or ``None`` if none is writable and safe.

    Returns
    -------
    pathlib.Path or None
        ``None`` when no location can be written, or when the location could be written by
        someone else (see the module's notes on safety).
    """
    return _locate()[0]


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
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    for old in path.parent.glob(f"{path.name.rsplit('-', 1)[0]}-*.py"):
        if old != path:  # stale entries of the same name
            with contextlib.suppress(OSError):
                old.unlink()


def _read_entry(path: Path) -> str:
    """Text of the entry at ``path``, checked on the open file; :class:`_Miss` if absent."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise _Miss("missing") from None
    except OSError as exc:  # ELOOP: a symbolic link planted in place of an entry
        raise _Unsafe(f"{path} cannot be opened safely ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise _Unsafe(f"{path} is not a regular file")
        _check_owner(st, str(path), 0o022)
        return f.read().decode("utf-8")


def _warn(reason: str) -> None:
    warnings.warn(f"hybridpd: code cache not used, generating in memory: {reason}",
                  UnsafeCacheWarning, stacklevel=3)


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

    Raises
    ------
    ValueError
        If ``name`` has other characters.

    Warns
    -----
    UnsafeCacheWarning
        If the cache directory or the entry could be written by someone else; the code is
        then generated in memory and the entry is never executed.
    """
    if not _NAME_RE.match(name):
        raise ValueError(f"name must contain only letters, digits, '_' and '.', got {name!r}")
    d, reason = _locate()
    if reason is not None:
        _warn(reason)
    path = None if d is None else d / f"{name}-{key}.py"
    if path is not None:
        try:
            return _execute(_read_entry(path), name, key, str(path))
        except _Unsafe as exc:
            _warn(str(exc))  # the directory is ours: the planted entry is replaced below
        except Exception:  # noqa: BLE001, S110 - a corrupt entry may fail in any way: regenerate
            pass
    body = generate()
    text = _HEADER.format(name=name, key=key,
                          digest=hashlib.sha256(body.encode()).hexdigest()) + body
    namespace = _execute(text, name, key, f"<generated {name}>")
    if path is not None:
        with contextlib.suppress(OSError):  # read-only or full disk: the code still works
            _write_atomic(path, text)
    return namespace
