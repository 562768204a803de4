"""Outputs: animated USD stages (:mod:`warpsim.io.usd`) and streaming HDF5 recordings (:mod:`warpsim.io.hdf5`).

Helpers shared by every output: the path checks made before a run starts, and the temporary names that
outputs are written under before they are renamed into place (``.NAME.PID.tmp.EXT`` beside the target;
ones left by a killed process are removed by the next output written there).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import stat
from pathlib import Path

STAGE_EXTENSIONS = (".usda", ".usdc", ".usdz")
"""File names a USD stage may take (text, binary, package)."""


def check_stage_path(path) -> Path:
    """Check that ``path`` can be written as a USD stage (raises ``OutputPathError``); here rather than in
    :mod:`warpsim.io.usd` so that checking a path does not load USD (seconds of start-up)."""
    return check_output_path(path, STAGE_EXTENSIONS, "USD")


class OutputPathError(ValueError):
    """An output path that cannot be written: unknown extension, missing or unwritable directory, not a file."""


class OutputWriteError(OSError):
    """Writing an output failed part-way (disk full, I/O error); the message says what was kept."""


SYSTEM_CAUSES = tuple(
    os.strerror(code) for code in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EROFS, errno.EACCES)
)
"""System error messages that name why a write failed; looked for in libraries' long error texts."""


def cause(text: str) -> str:
    """The cause in a library's error text: a system error message when one is named (HDF5 and USD bury it in
    file names, line numbers and buffer addresses), else the first line (at most 200 characters)."""
    for known in SYSTEM_CAUSES:
        if known in text:
            return known
    lines = text.strip().splitlines()
    return lines[0].strip()[:200] if lines else "unknown error"


def with_disk_state(detail: str, path) -> str:
    """``detail`` of a failed write to ``path``, prefixed with "No space left on device" when it names no system
    cause and less than 1 MiB is free beside ``path`` (libraries do not always say why a write failed)."""
    if detail in SYSTEM_CAUSES:
        return detail
    try:
        info = os.statvfs(Path(path).parent)
    except OSError:
        return detail
    if info.f_bavail * info.f_frsize < 1 << 20:
        return f"{os.strerror(errno.ENOSPC)}: {detail}"
    return detail


def reason(err: BaseException) -> str:
    """A short, one-line cause of an ``OSError`` (``No space left on device``), for error messages."""
    code = getattr(err, "errno", None)
    if isinstance(code, int) and code > 0:
        return os.strerror(code)
    return cause(str(err.args[0] if isinstance(err, KeyError) and err.args else err) or type(err).__name__)


def check_output_path(path, extensions: tuple[str, ...], kind: str) -> Path:
    """Check that ``path`` can be written as a ``kind`` output before anything is computed; returns it as a Path.

    It must end in one of ``extensions``; its directory must exist and take new files (a file is created
    there and removed again, which catches read-only mounts and immutable directories); an existing
    ``path`` must be a regular file that can be opened for writing. ``kind`` names the format in the
    message (``USD``, ``HDF5``). Raises :class:`OutputPathError`.
    """
    path = Path(path)
    if path.suffix.lower() not in extensions:
        choices = ", ".join(extensions[:-1]) + " or " + extensions[-1] if len(extensions) > 1 else extensions[0]
        raise OutputPathError(f"{path}: unknown {kind} extension {path.suffix!r}; use {choices}")
    directory = path.parent
    if not directory.resolve().is_dir():
        raise OutputPathError(f"{path}: directory {directory} does not exist")
    try:
        info = os.stat(path)
    except FileNotFoundError:
        info = None
    except OSError as err:
        raise OutputPathError(f"{path}: cannot be written ({reason(err)})") from None
    if info is not None and stat.S_ISDIR(info.st_mode):
        raise OutputPathError(f"{path}: is a directory")
    if info is not None and not stat.S_ISREG(info.st_mode):
        raise OutputPathError(f"{path}: exists and is not a regular file")
    probe = temporary_path(path, ".probe")
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        probe.unlink()
    except OSError as err:
        raise OutputPathError(f"{path}: cannot write in {directory} ({reason(err)})") from None
    if info is not None:
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))  # no truncation: only asks
        except OSError as err:
            raise OutputPathError(f"{path}: cannot be overwritten ({reason(err)})") from None
    return path


def temporary_path(path: Path, suffix: str | None = None) -> Path:
    """A name beside ``path`` for writing it before the rename: ``.NAME.PID.tmp.EXT`` (``EXT`` = ``suffix``,
    default ``path``'s, which tells writers such as USD the format)."""
    path = Path(path)
    ext = path.suffix if suffix is None else suffix
    return path.with_name(f".{path.name}.{os.getpid()}.tmp{ext}")


def remove_stale_temporaries(path: Path) -> list[Path]:
    """Remove the temporary files of ``path`` (see :func:`temporary_path`) whose process no longer runs
    (killed while writing); returns them."""
    path = Path(path)
    removed = []
    for candidate in path.parent.glob(f".{path.name}.*.tmp*"):
        pid_text = candidate.name[len(path.name) + 2 :].split(".", 1)[0]
        if not pid_text.isdigit() or int(pid_text) == os.getpid() or _alive(int(pid_text)):
            continue
        try:
            candidate.unlink()
            removed.append(candidate)
        except OSError:
            pass
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except OSError as err:
        return err.errno == errno.EPERM  # exists, owned by someone else
    return True


def same_file(a, b) -> bool:
    """True when paths ``a`` and ``b`` name the same existing file (or the same path)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(a).resolve() == Path(b).resolve()


def create_temporary(path, suffix: str | None = None) -> tuple[Path, int]:
    """Create the temporary file of ``path`` (:func:`temporary_path`) afresh and return ``(its path, a descriptor
    open for writing)``. Created with ``O_EXCL | O_NOFOLLOW``: a file or link planted under that name (in a shared
    folder such as /tmp) is removed first, never written through, so the output cannot land in someone else's file.
    Temporaries of killed processes are removed (:func:`remove_stale_temporaries`). Raises ``OSError``."""
    remove_stale_temporaries(path)
    tmp = temporary_path(path, suffix)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        return tmp, os.open(tmp, flags, 0o600)
    except FileExistsError:  # planted under our process's name: unlink removes the link, not what it names
        tmp.unlink()
        return tmp, os.open(tmp, flags, 0o600)


@contextlib.contextmanager
def replacing(path, what: str = "output", suffix: str | None = None):
    """Write ``path`` whole or not at all: yields a binary file open on a fresh temporary beside it
    (:func:`create_temporary`); when the block ends cleanly the file is synced, given the mode a new file gets
    (0666 less the umask) and renamed over ``path`` (a link at ``path`` is replaced, never followed). On any
    error the temporary is removed and ``path`` keeps what it held; an ``OSError`` (disk full) becomes
    :class:`OutputWriteError` naming ``path`` and ``what`` (``"table"``, ``"plot"``)."""
    path = Path(path)
    tmp = None
    try:
        tmp, fd = create_temporary(path, suffix)
        with os.fdopen(fd, "wb") as file:
            yield file
            file.flush()
            os.fsync(file.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
        tmp = None
    except OSError as err:
        raise OutputWriteError(f"{path}: could not write the {what} ({with_disk_state(reason(err), path)})") from None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()


class OutputLockedError(OSError):
    """Another process owns the output path."""


class OutputLock:
    """One owner per output path: an exclusive ``flock`` on ``.NAME.lock`` beside ``path``, held until
    :meth:`release` (or the end of the process: a killed owner's lock goes with it). For outputs replaced by a
    rename (a sweep's table and its journal), whose own file changes under a lock on it.

    The lock file is created without following a link and removed on release; a lock taken on a file that its
    previous owner removed meanwhile is taken again on the new one. Raises :class:`OutputLockedError` at once
    when another process holds it, ``OSError`` when the folder takes no file.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.lock_path = self.path.with_name(f".{self.path.name}.lock")
        flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
        while True:
            fd = os.open(self.lock_path, flags, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as err:
                os.close(fd)
                if err.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise OutputLockedError(err.errno, "another process is writing it") from None
                raise
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.lock_path, follow_symlinks=False))
            except FileNotFoundError:
                same = False
            if same:
                self.fd: int | None = fd
                return
            os.close(fd)  # its owner removed it between our open and our lock: take the new one

    def release(self) -> None:
        """Remove the lock file and give the lock back (safe to call twice)."""
        if self.fd is not None:
            with contextlib.suppress(OSError):
                self.lock_path.unlink()
            os.close(self.fd)
            self.fd = None
