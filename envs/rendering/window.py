"""The ``render_mode="human"`` window: a Tk window showing each frame, paced to real time.

Tk comes with Python; the project's OpenCV build has no GUI. Without a display the window
cannot open, and :class:`HumanWindow` says so when the env is made.
"""

from __future__ import annotations

import os
import time

import numpy as np


def display_available() -> bool:
    """True when a window can be shown (an X or Wayland display is set)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class HumanWindow:
    """A window that shows RGB frames at most ``fps`` times a second of wall time."""

    def __init__(self, title: str, fps: float) -> None:
        if not display_available():
            raise RuntimeError(
                "render_mode='human' needs a display (DISPLAY is not set); use "
                "render_mode='rgb_array' and save the frames, e.g. with "
                "gymnasium.wrappers.RecordVideo"
            )
        try:
            import tkinter
        except ImportError as err:
            raise RuntimeError(f"render_mode='human' needs tkinter: {err}") from err
        try:
            self._root = tkinter.Tk()
        except tkinter.TclError as err:
            raise RuntimeError(f"render_mode='human' could not open a window: {err}") from err
        self._root.title(title)
        self._label = tkinter.Label(self._root)
        self._label.pack()
        self._photo = None
        self._period = 1.0 / fps
        self._last = 0.0

    def show(self, frame: np.ndarray) -> None:
        """Show an RGB uint8 frame (H, W, 3), waiting out the rest of the frame period."""
        import tkinter

        height, width, _ = frame.shape
        ppm = b"P6 %d %d 255\n" % (width, height) + np.ascontiguousarray(frame).tobytes()
        self._photo = tkinter.PhotoImage(data=ppm, format="PPM")
        self._label.configure(image=self._photo)
        wait = self._period - (time.perf_counter() - self._last)
        if wait > 0:
            time.sleep(wait)
        self._root.update()
        self._last = time.perf_counter()

    def close(self) -> None:
        """Close the window; calling it again is harmless."""
        if self._root is not None:
            self._root.destroy()
            self._root = None
