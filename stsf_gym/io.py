"""Result files written atomically, so an interrupted run never leaves a half-written file; and
the checks that a command's output paths can be written, made before any work."""

from __future__ import annotations

import json
import math
import os
import secrets
from pathlib import Path
from typing import Any


def create_temporary(path: str | Path, suffix: str = ".tmp") -> tuple[int, Path]:
    """A new, empty temporary file beside ``path`` (``.<name>.<random><suffix>``), open for
    writing: its descriptor and path. Made as ``open`` makes a file, with mode ``0o666`` less
    the user's umask, so the file renamed over ``path`` is as readable as any other the user
    writes (``tempfile.mkstemp`` makes it ``0o600`` whatever the umask)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(4)}{suffix}"
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), tmp
        except FileExistsError:
            continue


def write_atomic(path: str | Path, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename;
    the file gets the mode the user's umask gives new files."""
    path = Path(path)
    fd, tmp = create_temporary(path)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def check_folder(folder: str | Path, flag: str) -> None:
    """Fail before any work when ``folder`` cannot be made or written (makes nothing; a probe
    file is created and removed in the nearest existing folder):
    :class:`NotADirectoryError` or :class:`PermissionError` naming ``flag``, the option that
    chose it."""
    folder = Path(folder).absolute()
    existing = folder
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise NotADirectoryError(f"{flag} {folder}: {existing} is not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise PermissionError(f"{flag} {folder}: {existing} is not writable")
    try:  # root passes os.access everywhere, also in a kernel folder (/proc) or a read-only mount
        handle, probe = create_temporary(existing / "write-probe")
    except OSError as err:
        message = f"{flag} {folder}: {existing} is not writable ({err.strerror})"
        raise PermissionError(message) from None
    os.close(handle)
    os.unlink(probe)


def check_file(file: str | Path, flag: str) -> None:
    """Fail before any work when ``file`` cannot be written: :class:`IsADirectoryError` for a
    folder of that name, else as :func:`check_folder` for its folder."""
    file = Path(file)
    if file.is_dir():
        raise IsADirectoryError(f"{flag} {file} is a folder; name the file to write")
    check_folder(file.absolute().parent, flag)


def remove_partial_writes(folder: str | Path) -> list[Path]:
    """Delete the temporary files that :func:`write_atomic` calls killed mid-write left under
    ``folder`` (``.<name>.<random>.tmp``; the file they were to replace is intact); return them."""
    found = (
        [p for p in Path(folder).rglob(".*.tmp") if p.is_file()] if Path(folder).is_dir() else []
    )
    for path in found:
        path.unlink(missing_ok=True)
    return found


def write_json(path: str | Path, obj: Any) -> Path:
    """Write ``obj`` as indented, strict JSON, atomically (numpy values as numbers; a NaN or
    infinity as ``null``: Python's ``NaN`` is no JSON, and other readers refuse it); return
    the path."""
    try:
        text = json.dumps(obj, indent=2, default=to_builtin, allow_nan=False)
    except ValueError:  # a non-finite number somewhere: the slow path, rarely taken
        text = json.dumps(_finite(obj), indent=2, default=to_builtin, allow_nan=False)
    return write_atomic(path, text + "\n")


def _finite(value: Any) -> Any:
    """``value`` with every non-finite float (numpy's too) replaced by None."""
    if hasattr(value, "tolist") and not isinstance(value, float):
        value = value.tolist()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(item) for item in value]
    return value


def save_figure(fig, path: str | Path, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG, atomically."""
    import io

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    return write_atomic(path, buffer.getvalue())


def markdown_table(rows: list[dict], columns: list[str] | None = None) -> str:
    """A GitHub-flavoured Markdown table of ``rows`` (dicts sharing keys); with no rows (a
    run whose every cell failed) and no ``columns``, a line saying so."""
    if not rows and not columns:
        return "No rows: nothing finished.\n"
    columns = columns or list(rows[0])
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(_cell(row.get(c, "")) for c in columns) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _cell(value: Any) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


def to_builtin(value: Any) -> Any:
    """``value`` (a numpy array or scalar) as the Python numbers and lists JSON holds."""
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"cannot write {type(value).__name__} as JSON")
