"""Every file the project writes goes through here: one set of rules for all outputs.

Why one helper: an output path is something a user typed (`-o`, `--csv`, `retain_file`, a
hand-out directory). A careless `open(path, "w")` follows a symlink, fills a device such as
`/dev/full`, or leaves a half-written file when the disk fills up; a careless "set aside"
renames a directory the user never named. The rules, for every writer:

1. The target is exactly what the user named. If it exists it must be a regular file; a
   symbolic link, a directory, a device (`/dev/full`), a FIFO or a socket is refused with one
   line, and nothing is written.
2. The data goes to a temporary file next to the target (`.NAME.<pid>-<random>.tmp`, same
   directory, so the rename cannot cross file systems), then is renamed over the target: a
   reader sees the old file or the new one, never half of one. `durable=True` also fsyncs the
   data and the directory (retain files: a power loss keeps the old or the new file).
3. Nothing else is renamed or removed. On failure the only file removed is our own temporary
   one; the old target is left as it was. Missing parent directories are created (only
   directories, and never over an existing file) unless `parents=False`.
4. Every failure is an `OutputError` (a PlcLabError) whose message is one line:
   `PATH: cannot write: REASON` or `PATH: exists and is not a regular file (...)`.

How to use it:
- bytes or text already in memory: `write_bytes(path, data)` / `write_text(path, text)`;
- a writer that streams to a file object: `with open_atomic(path) as f: ...`
  (text mode by default, `binary=True` for bytes); the file appears only if the block ends
  without an exception;
- before a long computation whose result goes to a file (a simulation, a grading run):
  `check_output(path)` refuses a bad target up front, so the user is not told after the work;
- a process killed between creating its temporary file and the rename leaves that temporary
  behind: `remove_stale_temporaries(path)` removes the ones whose process is gone (call it
  at start-up of whatever owns the file, e.g. the retain store).

Inputs a user names (a student's ST file, a traffic log) are untrusted too: `read_input(path,
limit)` reads one only if it is a regular file of at most `limit` bytes, and says so before
reading anything else: a FIFO would block forever, `/dev/zero` never ends, a 3 GB file would
be read whole. A symbolic link the user typed is followed (they named it); callers that walk
a folder of other people's files (grade-class) pass `follow_symlinks=False`.
"""
from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import stat
from pathlib import Path
from typing import IO, Iterator, Union

from plclab.errors import PlcLabError

PathLike = Union[str, "os.PathLike[str]"]

_TEMP_RE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)-[0-9a-f]{8}\.tmp$")


class OutputError(PlcLabError):
    """An output that cannot or must not be written; str() is the one line shown."""


class InputError(PlcLabError):
    """An input that cannot or must not be read; str() is the reason (the caller adds the file)."""


_KINDS = ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a directory"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    """What a non-regular file is, as the one-line errors name it ("a FIFO")."""
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _reason(exc: OSError) -> str:
    if exc.errno in (errno.ENOTDIR, errno.EEXIST):
        return "a part of the path is a file, not a directory"
    return exc.strerror or str(exc)


def existing_kind(path: PathLike) -> str | None:
    """None if `path` does not exist or is a regular file; else what it is ("a directory",
    "a symbolic link", "a character device"...). The link itself is looked at, not its target."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return None
    except NotADirectoryError:
        return None          # a parent is a file: reported when the directory is made
    except OSError as exc:
        raise OutputError(f"{os.fspath(path)}: cannot write: {_reason(exc)}") from None
    return None if stat.S_ISREG(mode) else _kind(mode)


def check_output(path: PathLike, parents: bool = True) -> Path:
    """Refuse a target that must not be written, before any work is done; returns the Path.

    Checks rule 1 and that the directory exists or can be made (no file in the way); it
    creates nothing. A target that passes may still fail when written (disk full,
    permissions): the writers report that.
    """
    p = Path(path)
    if not os.fspath(p):
        raise OutputError("an empty output path")
    kind = existing_kind(p)
    if kind is not None:
        raise OutputError(f"{p}: exists and is {kind}; refusing to replace it (name a regular file)")
    parent = p.parent
    while True:
        try:
            mode = os.stat(parent).st_mode
        except FileNotFoundError:
            if not parents:
                raise OutputError(f"{p}: cannot write: no such directory '{p.parent}'") from None
            if parent == parent.parent:
                break
            parent = parent.parent
            continue
        except NotADirectoryError:
            raise OutputError(f"{p}: cannot write: a part of the path is a file, not a directory") from None
        except OSError as exc:
            raise OutputError(f"{p}: cannot write: {_reason(exc)}") from None
        if not stat.S_ISDIR(mode):
            raise OutputError(f"{p}: cannot write: '{parent}' is a file, not a directory")
        break
    return p


PROBE_BYTES = 256 * 1024     # check_writable: a folder that cannot take this much is full


def check_writable(directory: PathLike) -> Path:
    """Before a long computation whose results go into `directory`: create it if missing (only
    directories, as the writers would) and write, sync and remove a temporary file of
    PROBE_BYTES there, so a read-only or full folder is refused (one line) now, not after the
    work. Nothing but our own temporary file is created or removed."""
    d = Path(directory)
    check_output(d / ".probe")                 # no file where a directory of the path must be
    tmp = temporary_name(d / ".probe")
    fd = -1
    try:
        d.mkdir(parents=True, exist_ok=True)
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o600)
        data = bytes(PROBE_BYTES)
        written = 0
        while written < len(data):
            written += os.write(fd, data[written:])
        os.fsync(fd)
    except OSError as exc:
        raise OutputError(f"{d}: cannot write: {_reason(exc)}") from None
    finally:
        if fd >= 0:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    return d


def user_cache_dir(*parts: str) -> Path:
    """This user's cache folder for plclab ($XDG_CACHE_HOME/plclab/..., default
    ~/.cache/plclab/...): what is worked out once and reused by every later process (native
    builds, the ST parser's tables). Not created here."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base, "plclab", *parts)


def temporary_name(path: PathLike) -> Path:
    """A fresh name for the temporary file of `path` (same directory, hidden, tagged with
    this process's id so a later start can tell a stale one from a live one)."""
    p = Path(path)
    return p.with_name(f".{p.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp")


@contextlib.contextmanager
def open_atomic(path: PathLike, binary: bool = False, durable: bool = False,
                parents: bool = True, encoding: str = "utf-8", newline: str | None = None) -> Iterator[IO]:
    """A file object for writing `path` by the rules above; the target is replaced when the
    block ends normally, and untouched (no temporary left) when it raises."""
    p = check_output(path, parents)
    try:
        if parents:
            p.parent.mkdir(parents=True, exist_ok=True)
        old_mode = None
        with contextlib.suppress(FileNotFoundError):
            old_mode = stat.S_IMODE(os.lstat(p).st_mode)
        tmp = temporary_name(p)
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(f"{p}: cannot write: {_reason(exc)}") from None
    try:
        if old_mode is not None:
            os.fchmod(fd, old_mode)          # replacing a file keeps its permissions
        mode = "wb" if binary else "w"
        kwargs = {} if binary else {"encoding": encoding, "newline": newline}
        with os.fdopen(fd, mode, **kwargs) as f:
            fd = -1
            yield f
            f.flush()
            if durable:
                os.fsync(f.fileno())
        kind = existing_kind(p)              # someone may have put something there meanwhile
        if kind is not None:
            raise OutputError(f"{p}: exists and is {kind}; refusing to replace it (name a regular file)")
        os.replace(tmp, p)
        tmp = None
        if durable:
            _fsync_directory(p.parent)
    except OSError as exc:
        raise OutputError(f"{p}: cannot write: {_reason(exc)}") from None
    finally:
        if fd >= 0:
            os.close(fd)
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def write_bytes(path: PathLike, data: bytes, durable: bool = False, parents: bool = True) -> Path:
    """Write `data` to `path` by the rules above; returns the Path written."""
    with open_atomic(path, binary=True, durable=durable, parents=parents) as f:
        f.write(data)
    return Path(path)


def write_text(path: PathLike, text: str, durable: bool = False, parents: bool = True,
               encoding: str = "utf-8") -> Path:
    """Write `text` to `path` (UTF-8, newlines as given) by the rules above."""
    return write_bytes(path, text.encode(encoding), durable=durable, parents=parents)


def _fsync_directory(directory: Path) -> None:
    """Make the rename itself durable (POSIX); a file system that cannot is left as it is."""
    try:
        dfd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(dfd)
    except OSError:
        pass
    finally:
        os.close(dfd)


def process_alive(pid: int) -> bool:
    """Whether process `pid` runs (ours counts); used to tell a stale temporary from a live one."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError, ValueError):
        return False                         # gone, or a number no process can have
    except PermissionError:
        return True                          # someone else's live process
    return True


def stale_temporaries(path: PathLike) -> list[Path]:
    """Temporary files of `path` left by processes that no longer run (killed between
    writing and renaming). Only regular files named by this module's pattern are listed."""
    p = Path(path)
    try:
        entries = list(os.scandir(p.parent if os.fspath(p.parent) else "."))
    except OSError:
        return []
    stale = []
    for entry in entries:
        m = _TEMP_RE.match(entry.name)
        if m is None or m.group("name") != p.name:
            continue
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
        except OSError:
            continue
        if not process_alive(int(m.group("pid"))):
            stale.append(p.parent / entry.name)
    return sorted(stale)


def remove_stale_temporaries(path: PathLike) -> list[Path]:
    """Remove the stale temporaries of `path` (see stale_temporaries); returns those removed."""
    removed = []
    for tmp in stale_temporaries(path):
        with contextlib.suppress(OSError):
            os.unlink(tmp)
            removed.append(tmp)
    return removed


# ---------------------------------------------------------------------------- inputs
def read_input(path: PathLike, limit: int, follow_symlinks: bool = True) -> bytes:
    """The bytes of the user's input file `path`, read only if it is a regular file of at most
    `limit` bytes. Raises InputError whose str() is the reason alone ("no such file", "not a
    regular file (a FIFO)", "file too large (N bytes; the limit is M)"), for the caller to
    put after the file's name in its own format (`FILE:1:1: error: REASON` for ST).

    The kind is checked with stat() before opening (a device is never opened), the open is
    non-blocking (a FIFO swapped in meanwhile cannot hang it) and fstat() confirms what was
    opened; at most `limit` + 1 bytes are ever read (a file that grows, a /proc file whose
    size says 0)."""
    name = os.fspath(path)
    try:
        st = os.stat(name) if follow_symlinks else os.lstat(name)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(_not_regular(st.st_mode))
        if st.st_size > limit:
            raise InputError(_too_large(st.st_size, limit))
        flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
        if not follow_symlinks:
            flags |= getattr(os, "O_NOFOLLOW", 0)
        fd = os.open(name, flags)
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError("no such file") from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise InputError(_not_regular(stat.S_IFLNK)) from None
        raise InputError(f"cannot read file: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(_not_regular(st.st_mode))
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit:
            raise InputError(_too_large(max(size, st.st_size), limit, more=size > st.st_size))
        return b"".join(chunks)
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def _not_regular(mode: int) -> str:
    return f"not a regular file ({_kind(mode)}); refused without reading it"


def _too_large(size: int, limit: int, more: bool = False) -> str:
    return f"file too large ({'more than ' if more else ''}{size} bytes; the limit is {limit})"
