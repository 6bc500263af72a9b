"""Quiet PyBullet: its C code prints banners (``pybullet build time``, ``argv[0]=``, the EGL
device and OpenGL vendor lines) straight to file descriptors 1 and 2, past ``sys.stdout``.

:class:`quiet_c_output` captures both descriptors while PyBullet loads, a client connects or
disconnects and a plugin loads. Set ``STSF_GYM_VERBOSE=1`` (the CLI's ``--verbose``) to see
them. While a block runs, other threads' writes to those descriptors are captured too; the
blocks are short and run when an env is built or closed.
"""

from __future__ import annotations

import ctypes
import os
import sys
import tempfile
from types import TracebackType

#: Environment variable that keeps PyBullet's banners (any value but "" or "0").
VERBOSE_ENV = "STSF_GYM_VERBOSE"
_FDS = (1, 2)

try:
    _LIBC = ctypes.CDLL(None)
except OSError:  # pragma: no cover - platforms without a process-wide C library handle
    _LIBC = None


def verbose() -> bool:
    """True when PyBullet's banners should be shown (``STSF_GYM_VERBOSE`` set)."""
    return os.environ.get(VERBOSE_ENV, "") not in ("", "0")


def _flush() -> None:
    """Flush Python's and C's stdio buffers, so text lands on the descriptor it was meant for."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    if _LIBC is not None:
        _LIBC.fflush(None)


class quiet_c_output:
    """Capture what is written to file descriptors 1 and 2 inside the block.

    The text is dropped when the block ends normally and written to stderr when it raises, so
    a failing plugin load still explains itself. A no-op when :func:`verbose` is true.
    """

    def __enter__(self) -> quiet_c_output:
        self._saved: list[int] = []
        if verbose():
            return self
        _flush()
        self._sink = tempfile.TemporaryFile()
        self._saved = [os.dup(fd) for fd in _FDS]
        for fd in _FDS:
            os.dup2(self._sink.fileno(), fd)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if not self._saved:
            return
        _flush()
        for fd, saved in zip(_FDS, self._saved, strict=True):
            os.dup2(saved, fd)
            os.close(saved)
        self._saved = []
        with self._sink:
            if kind is not None:
                self._sink.seek(0)
                os.write(2, self._sink.read())
