"""Low-level safety for HDF5 recordings: one writer per file, bounded reads, killed writers' flags, full disks.

* :class:`WriterLock`: an exclusive lock a writer holds on its recording for as long as it writes. HDF5's own
  lock is released by single-writer/multiple-reader (SWMR) writers so that readers can open the file, which
  also lets a second writer truncate it; this lock is an open-file-description (OFD) record lock on Linux,
  which HDF5's ``flock`` locks do not see, so SWMR readers still open the file while a second writer is
  refused. Elsewhere it falls back to ``flock`` (readers then disable HDF5's locking, as warpsim's do).
* :func:`open_for_reading`: opens a recording for SWMR reading with a bounded number of metadata read
  attempts. HDF5 retries a metadata block whose checksum fails up to 100 times with growing sleeps when a
  file is opened for SWMR reading (a live writer may be half-way through it); a corrupted file then hangs a
  reader for minutes. With no live writer there is nothing to wait for, so one attempt is made.
* :func:`probe_metadata`: HDF5 (1.14) can loop for minutes or for ever, holding the interpreter's lock so that no
  signal reaches Python, on a file whose global heap is damaged (a variable-length string's object with a corrupted
  size); a forked child reads every attribute first and is killed after a few seconds, and the file is refused.
* :func:`clear_status_flags`: a writer killed outright (SIGKILL, power loss) leaves the "open for (SWMR)
  write" flags set in the superblock, and plain ``h5py.File(path, "r")`` refuses the file. A resume clears
  them under its lock, as ``h5clear -s`` does.
* :func:`abandon`: after a failed write (disk full), HDF5's cached metadata cannot reach the disk, and
  closing the file, or the library's own clean-up at exit, crashes. The file descriptor is pointed at
  ``/dev/null`` so that the close completes; the file keeps what was written before the failure.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import os
import signal
import struct
import threading
import time
from pathlib import Path

import h5py

SIGNATURE = b"\x89HDF\r\n\x1a\n"
_READ_ATTEMPTS_LIVE = 100  # HDF5's default for SWMR readers


class LockedError(OSError):
    """Another process is writing the recording."""


def _ofd_lock(fd: int, kind: int, command: int) -> bytes:
    """``fcntl`` an OFD lock request ``kind`` (``F_WRLCK``/``F_UNLCK``) over the whole file; returns the reply."""
    request = struct.pack("hhqqi4x", kind, os.SEEK_SET, 0, 0, 0)  # struct flock: type, whence, start, len, pid
    return fcntl.fcntl(fd, command, request)


_HAVE_OFD = hasattr(fcntl, "F_OFD_SETLK") and hasattr(fcntl, "F_OFD_GETLK")


class WriterLock:
    """Hold an exclusive writer's lock on ``path`` (created empty when missing and ``create``).

    Raises :class:`LockedError` at once when another process holds it, and ``OSError`` when the file cannot be
    opened for writing (``ELOOP`` when ``path`` is a symbolic link: a recording is never written through one).
    The lock lasts until :meth:`release` or the end of the process (a killed writer's lock goes with it).
    """

    def __init__(self, path, create: bool):
        self.path = Path(path)
        # never through a link: a link planted at the recording's name would have its target truncated and rewritten
        flags = os.O_RDWR | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOFOLLOW", 0)
        self.created = False  # True when this lock made the (empty) file
        self.fd: int | None = None
        if create:
            try:
                self.fd = os.open(self.path, flags | os.O_CREAT | os.O_EXCL, 0o666)
                self.created = True
            except FileExistsError:
                pass
        if self.fd is None:
            self.fd = os.open(self.path, flags)
        try:
            if _HAVE_OFD:
                _ofd_lock(self.fd, fcntl.F_WRLCK, fcntl.F_OFD_SETLK)
            else:  # pragma: no cover - not Linux
                fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(self.fd)
            self.fd = None
            if err.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise LockedError(err.errno, "another process is writing it") from None
            raise

    def release(self, remove_created: bool = False) -> None:
        """Give the lock back (safe to call twice); ``remove_created``: first delete the file if this lock made it
        (a run that stopped before recording anything)."""
        if self.fd is not None:
            if remove_created and self.created:
                self.path.unlink(missing_ok=True)
            os.close(self.fd)
            self.fd = None


def writer_active(path) -> bool:
    """True when a process holds the :class:`WriterLock` of ``path`` (a live run is writing it)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError:
        return False
    try:
        if _HAVE_OFD:
            reply = _ofd_lock(fd, fcntl.F_WRLCK, fcntl.F_OFD_GETLK)
            return struct.unpack("hhqqi4x", reply)[0] != fcntl.F_UNLCK
        try:  # pragma: no cover - not Linux
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except OSError:  # pragma: no cover
            return True
        return False  # pragma: no cover
    finally:
        os.close(fd)


def _hdf5_library():
    """The HDF5 shared library h5py is linked to (for the one property h5py does not expose), or None."""
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                name = line.rsplit("/", 1)[-1]
                if name.startswith("libhdf5") and not name.startswith("libhdf5_hl"):
                    lib = ctypes.CDLL(line.split(None, 5)[-1].strip())
                    lib.H5Pset_metadata_read_attempts.argtypes = [ctypes.c_int64, ctypes.c_uint]
                    lib.H5Pset_metadata_read_attempts.restype = ctypes.c_int
                    return lib
    except (OSError, AttributeError):
        pass
    return None


_LIBRARY: list = []


def _read_attempts_setter():
    if not _LIBRARY:
        _LIBRARY.append(_hdf5_library())
    return _LIBRARY[0]


def _access(attempts: int):
    """File access properties: latest format, strong close, HDF5 locking off, ``attempts`` metadata reads."""
    fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
    fapl.set_fclose_degree(h5py.h5f.CLOSE_STRONG)
    fapl.set_libver_bounds(h5py.h5f.LIBVER_LATEST, h5py.h5f.LIBVER_LATEST)
    fapl.set_file_locking(False, True)
    lib = _read_attempts_setter()
    if lib is not None:
        lib.H5Pset_metadata_read_attempts(fapl.id, attempts)
    return fapl


def open_for_reading(path, live: bool) -> h5py.File:
    """Open ``path`` read-only for SWMR reading, HDF5 locking off; ``live`` (a writer is running) allows
    HDF5's usual metadata read retries, otherwise one attempt, so that a corrupted file fails at once."""
    fapl = _access(_READ_ATTEMPTS_LIVE if live else 1)
    return h5py.File(h5py.h5f.open(os.fsencode(path), h5py.h5f.ACC_RDONLY | h5py.h5f.ACC_SWMR_READ, fapl=fapl))


def open_for_writing(path, create: bool = False, swmr: bool = True) -> h5py.File:
    """Create (truncating) or open ``path`` for writing, HDF5 locking off (the caller holds a :class:`WriterLock`)
    and one metadata read attempt. ``swmr``: open straight into SWMR write mode (not with ``create``). HDF5
    honours the attempts only for a file opened in SWMR mode; one switched to it later (``swmr_mode = True``)
    retries a damaged block for minutes, so writers set their file up, close it and open it again this way."""
    fapl = _access(1)
    name = os.fsencode(path)
    if create:
        return h5py.File(h5py.h5f.create(name, h5py.h5f.ACC_TRUNC, fapl=fapl))
    flags = h5py.h5f.ACC_RDWR | (h5py.h5f.ACC_SWMR_WRITE if swmr else 0)
    return h5py.File(h5py.h5f.open(name, flags, fapl=fapl))


def _rot(x: int, k: int) -> int:
    return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF


_MIX_ORDER = ((0, 2, 1), (1, 0, 2), (2, 1, 0)) * 2  # (a, c, b), (b, a, c), (c, b, a) twice


def lookup3(data: bytes, initval: int = 0) -> int:
    """Bob Jenkins' lookup3 ``hashlittle``: the checksum HDF5 puts on its metadata (superblock v2/v3)."""
    m = 0xFFFFFFFF
    a = b = c = (0xDEADBEEF + len(data) + initval) & m
    n, k = len(data), 0
    while n > 12:
        a = (a + int.from_bytes(data[k : k + 4], "little")) & m
        b = (b + int.from_bytes(data[k + 4 : k + 8], "little")) & m
        c = (c + int.from_bytes(data[k + 8 : k + 12], "little")) & m
        v = [a, b, c]
        for (x, y, z), r in zip(_MIX_ORDER, (4, 6, 8, 16, 19, 4), strict=True):  # lookup3's mix()
            v[x] = ((v[x] - v[y]) & m) ^ _rot(v[y], r)
            v[y] = (v[y] + v[z]) & m
        a, b, c = v
        n, k = n - 12, k + 12
    if n == 0:
        return c
    tail = data[k:] + bytes(12 - n)
    a = (a + int.from_bytes(tail[0:4], "little")) & m
    b = (b + int.from_bytes(tail[4:8], "little")) & m
    c = (c + int.from_bytes(tail[8:12], "little")) & m
    c = (c ^ b) - _rot(b, 14) & m
    a = (a ^ c) - _rot(c, 11) & m
    b = (b ^ a) - _rot(a, 25) & m
    c = (c ^ b) - _rot(b, 16) & m
    a = (a ^ c) - _rot(c, 4) & m
    b = (b ^ a) - _rot(a, 14) & m
    c = (c ^ b) - _rot(b, 24) & m
    return c


def _superblock(f) -> tuple[bytes, int] | None:
    """``(first bytes, length of the checksummed part)`` of a version 2 or 3 superblock at the start of the open
    file ``f`` whose stored checksum holds; None for anything else (then nothing is changed)."""
    f.seek(0)
    head = f.read(64)
    if len(head) < 13 or head[:8] != SIGNATURE or head[8] not in (2, 3):
        return None
    end = 12 + 4 * head[9]  # signature, version, sizes, flags, then four addresses of size_of_offsets bytes
    if len(head) < end + 4 or int.from_bytes(head[end : end + 4], "little") != lookup3(head[:end]):
        return None
    return head, end


def status_flags(path) -> int:
    """The superblock's status flags of ``path`` (0: closed cleanly; bit 0 open for write, bit 2 for SWMR write),
    or 0 when the superblock is not a version 2 or 3 one whose checksum holds."""
    with open(path, "rb") as f:
        found = _superblock(f)
    return found[0][11] if found is not None else 0


def clear_status_flags(path) -> bool:
    """Clear the superblock's "open for write / SWMR write" flags that a killed writer left (``h5clear -s``).

    Only for a file whose :class:`WriterLock` the caller holds. Handles superblock versions 2 and 3 at the start
    of the file (what warpsim writes) and checks the stored checksum before changing anything. Returns True when
    flags were cleared, False when none were set or the superblock is not one it knows (left untouched).
    """
    with open(path, "r+b") as f:
        found = _superblock(f)
        if found is None or found[0][11] == 0:
            return False
        head, end = found
        block = bytearray(head[:end])
        block[11] = 0
        f.seek(11)
        f.write(b"\0")
        f.seek(end)
        f.write(lookup3(bytes(block)).to_bytes(4, "little"))
        f.flush()
        os.fsync(f.fileno())
    return True


def extend_to_stored_end(path) -> bool:
    """Grow ``path`` with zeros up to the end of file its superblock records, when a failed write (a file-size
    limit, a full disk) left it shorter: HDF5 refuses to open such a file for writing ("truncated file"). The
    space added belongs to writes that never completed, after the last checkpoint; whatever a reader then
    finds there fails its checksums. Only under the caller's :class:`WriterLock`; superblock versions 2 and 3.
    Returns True when the file was extended."""
    with open(path, "r+b") as f:
        found = _superblock(f)
        if found is None:
            return False
        head, size = found[0], found[0][9]
        base = int.from_bytes(head[12 : 12 + size], "little")
        stored = base + int.from_bytes(head[12 + 2 * size : 12 + 3 * size], "little")
        if os.fstat(f.fileno()).st_size >= stored:
            return False
        f.truncate(stored)
    return True


def abandon(file: h5py.File) -> None:
    """Close ``file`` after a write to it failed, leaving on disk what was written before (see module notes)."""
    try:
        fd = file.id.get_vfd_handle()
    except Exception:  # noqa: BLE001 - any failure: close as well as we can
        fd = None
    if isinstance(fd, int) and fd >= 0:
        null = os.open(os.devnull, os.O_RDWR)
        os.dup2(null, fd)
        os.close(null)
    try:
        file.close()
    except Exception:  # noqa: BLE001 - writes now go nowhere; nothing more can fail that matters
        pass


PROBE_SECONDS = 10.0
"""[s] how long :func:`probe_metadata` lets HDF5 read a recording's attributes before it calls the file damaged."""


def probe_metadata(path, seconds: float = PROBE_SECONDS) -> None:
    """Raise ``OSError`` when HDF5 does not finish reading every attribute of ``path`` (opened as a reader with no
    live writer) within ``seconds``, or crashes reading them: a forked child reads them and is killed past the
    deadline (also when the wait is interrupted); a child killed by a signal of its own (a segmentation fault in the
    library) means the file would crash the caller too. Errors the child meets are left to the caller's own reading
    (which reports them). Nothing is
    probed without ``os.fork``, with other threads running (a fork copies only the caller's thread, and one of the
    others might hold h5py's lock), or when the fork or the wait itself fails."""
    if not hasattr(os, "fork") or threading.active_count() > 1:
        return
    try:
        pid = os.fork()
    except OSError:
        return
    if pid == 0:  # the child: read, then leave without running the parent's clean-up
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        try:
            with open_for_reading(path, False) as f:
                dict(f.attrs)
                f.visititems(lambda _name, item: dict(item.attrs))
        except BaseException:  # noqa: BLE001, S110 - the parent reads the file again and reports what is wrong
            pass
        os._exit(0)
    deadline = time.monotonic() + seconds
    done = False
    try:
        while (status := os.waitpid(pid, os.WNOHANG)) == (0, 0):
            if time.monotonic() > deadline:
                raise OSError(f"HDF5 did not finish reading its attributes in {seconds:g} s: a damaged heap")
            time.sleep(0.002)
        done = True
        if os.WIFSIGNALED(status[1]):  # the library itself crashed on the file: reading it here would crash too
            name = signal.Signals(os.WTERMSIG(status[1])).name
            raise OSError(f"HDF5 crashed ({name}) reading its attributes: a damaged file")
    except ChildProcessError:  # someone else reaped it (SIGCHLD ignored): nothing to say about the file
        done = True
    finally:
        if not done:  # past the deadline, or the wait was interrupted: the child must not loop on for ever
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
