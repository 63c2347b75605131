"""Output files a full disk cannot leave half-written: a CSV is cut back to its last whole row (and says how
many it holds), any other file is written aside and renamed, so it is whole under its name or absent.
A failure is a WriteFailed (one line, exit 2), never a traceback."""

from __future__ import annotations

import contextlib
import io
import os
import re
import secrets
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from sim.errors import WriteFailed
from sim.io import netcdf
from sim.system.frame import csv_line

T = TypeVar("T")
TEMPORARY = re.compile(r"_.+\.[0-9a-f]{8}\.partial(\.[a-z0-9]+)?")
"""The names `write_whole` gives its temporaries: a leading '_' (pyarrow and pandas skip such files when they read
a folder as one table, so a killed write never spoils the folder), 8 random hex digits, then '.partial'."""


def reason(e: OSError) -> str:
    """The system's words for the error ('No space left on device'), not a library's wrapping of them."""
    return os.strerror(e.errno) if e.errno else (e.strerror or str(e).splitlines()[0])


def _stamp(path: Path) -> tuple | None:
    """What tells one version of a file from another (its inode, time and size), or None where there is none."""
    try:
        s = path.stat()
    except OSError:
        return None
    return s.st_ino, s.st_mtime_ns, s.st_size


class LineFile:
    """A text file written in whole lines: they collect in memory and reach the disk in blocks of BLOCK bytes
    through os.write, whose count of bytes written is exact (a buffered file's is not); when a write fails, the
    file is cut back to its last whole line and WriteFailed raised. `lines` counts the whole lines on the disk.

    The lines go to a temporary beside `path` (named as TEMPORARY matches) renamed over `path` when the file is closed,
    after a failure or Ctrl-C too (the rows so far): a reader never sees half a file under the name, and of two runs
    writing one name each leaves its whole file, the later one's under the name. `replaced` then says what was there."""

    BLOCK = io.DEFAULT_BUFFER_SIZE  # as often as a buffered file would: a killed run loses no more

    def __init__(self, path: str | Path):
        self.path = str(path)
        target = Path(path)
        self._before = _stamp(target)
        self._tmp = str(target.parent / f"_{target.name}.{secrets.token_hex(4)}.partial")
        self.replaced = ""
        """After close: '' (a new file), 'the earlier file', or 'the file another run wrote there while this one ran'."""
        try:
            self._fd: int | None = os.open(self._tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except OSError as e:
            raise WriteFailed(self.path, reason(e)) from None
        self._pending: list[bytes] = []
        self._size = 0
        self.end = 0
        """Bytes on the disk, all of them whole lines."""
        self.lines = 0

    def header(self, columns: list[str]) -> None:
        self.write(csv_line(columns))

    def row(self, values) -> None:
        self.write(csv_line(values))

    def write(self, line: str) -> None:
        data = line.encode() + b"\n"
        self._pending.append(data)
        self._size += len(data)
        if self._size >= self.BLOCK:
            self.flush()

    def flush(self) -> None:
        data = memoryview(b"".join(self._pending))
        self._pending, self._size = [], 0
        done = 0
        try:
            while done < len(data):
                done += os.write(self._fd, data[done:])
        except BaseException as e:  # a second Ctrl-C too: whatever stops the write, the file ends on a whole line
            self._cut(data[:done])
            if isinstance(e, OSError):
                raise WriteFailed(self.path, reason(e)) from None
            raise
        self.end += len(data)
        self.lines += data.tobytes().count(b"\n")

    def _cut(self, written: memoryview) -> None:
        whole = bytes(written).rfind(b"\n") + 1
        self.end += whole
        self.lines += bytes(written[:whole]).count(b"\n")
        try:
            os.ftruncate(self._fd, self.end)
        except OSError:
            pass  # the count stays true of the whole lines; only a fragment after them may stay

    def close(self) -> None:
        """The lines still in memory written, then the file closed (also after a failure, which it does not repeat)."""
        if self._fd is None:
            return
        try:
            self.flush()
        finally:
            self.abandon()

    def abandon(self) -> None:
        """Closed without writing what is still in memory (after a failure: the disk is full), and put under its name."""
        if self._fd is not None:
            fd, self._fd = self._fd, None
            self._pending, self._size = [], 0
            try:
                os.close(fd)
            except OSError:
                pass
            self._publish()

    def _publish(self) -> None:
        now = _stamp(Path(self.path))
        self.replaced = (
            "" if now is None else "the earlier file" if now == self._before else "the file another run wrote there while this one ran"
        )
        try:
            os.replace(self._tmp, self.path)
        except OSError as e:
            raise WriteFailed(self.path, f"{reason(e)} (its rows are in {self._tmp})") from None


class NetcdfFile:
    """A run's rows as netCDF (sim/io/netcdf.py), LineFile's counterpart: the rows collect in memory and the file is
    written aside and renamed when it is closed, or abandoned after a Ctrl-C, a divergence or a failure (the rows so
    far: a result is never lost to a stop; a killed process, SIGKILL, loses them, where a CSV keeps its whole rows)."""

    def __init__(self, path: str | Path, scene: dict, history: str):
        self.path, self._scene, self._history = str(path), scene, history
        self._before = _stamp(Path(path))
        self._columns: list[str] = []
        self._rows: list = []
        self._open = True
        self.lines = 0
        """As LineFile's: the header and the rows in the file once written (0 before)."""
        self.replaced = ""

    def header(self, columns: list[str]) -> None:
        self._columns = list(columns)

    def row(self, values) -> None:
        self._rows.append(values)

    @property
    def rows(self) -> int:
        """The rows collected so far."""
        return len(self._rows)

    def close(self) -> None:
        if not self._open:
            return
        self._open = False
        ds = netcdf.dataset(self._columns, self._rows, self._scene, self._history)
        now = _stamp(Path(self.path))
        write_whole(self.path, lambda tmp: netcdf.write(ds, tmp))
        self.lines = 1 + len(self._rows)
        self.replaced = (
            "" if now is None else "the earlier file" if now == self._before else "the file another run wrote there while this one ran"
        )

    abandon = close


def write_whole(path: str | Path, write: Callable[[str], T], suffix: str = "") -> T:
    """`write(temporary)` into a new file beside `path`, renamed over `path` once whole: `path` is whole or as it was.
    Returns what `write` returned. The temporary (named as TEMPORARY matches; `suffix` after it, e.g. '.mp4' for a
    writer that reads the format from the name) is removed on any failure."""
    path = Path(path)
    tmp = str(path.parent / f"_{path.name}.{secrets.token_hex(4)}.partial{suffix}")  # made by `write`: the user's umask applies
    try:
        result = write(tmp)
        os.replace(tmp, path)
        return result
    except OSError as e:
        raise WriteFailed(path, reason(e)) from None
    finally:
        with contextlib.suppress(OSError):  # gone already (renamed), or not there to remove
            os.unlink(tmp)


def temporaries(folder: Path) -> list[Path]:
    """Temporaries `write_whole` left in `folder` (a write killed before its rename)."""
    return [p for p in folder.glob("_*.partial*") if TEMPORARY.fullmatch(p.name) and p.is_file()]
