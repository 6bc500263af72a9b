"""Videos of rendered frames: MP4 (H.264 through imageio-ffmpeg's bundled ffmpeg), or an
animated GIF through Pillow when no encoder is installed. Written atomically: the file appears
complete under its name or not at all."""

from __future__ import annotations

import os
from pathlib import Path
from types import TracebackType

import numpy as np

from stsf_gym.io import create_temporary


def mp4_available() -> bool:
    """True when imageio-ffmpeg (with its ffmpeg) is installed."""
    try:
        import imageio_ffmpeg

        return Path(imageio_ffmpeg.get_ffmpeg_exe()).is_file()
    except (ImportError, RuntimeError):
        return False


class VideoWriter:
    """``with VideoWriter(stem, fps) as video: video.append(frame)`` writes ``stem.mp4`` (or
    ``stem.gif`` without an encoder); :attr:`path` is the file. Frames are RGB uint8 arrays of
    one size; MP4 frames stream to the encoder, GIF frames are kept as palette images."""

    def __init__(self, stem: str | Path, fps: float, mp4: bool | None = None) -> None:
        self.fps = fps
        self.mp4 = mp4_available() if mp4 is None else mp4
        self.path = Path(stem).with_suffix(".mp4" if self.mp4 else ".gif")
        self._encoder = None
        self._gif: list = []
        self.frames = 0

    def __enter__(self) -> VideoWriter:
        fd, self._tmp = create_temporary(self.path.with_suffix(""), self.path.suffix)
        os.close(fd)
        return self

    def append(self, frame: np.ndarray) -> None:
        """Add one frame (H, W, 3) uint8."""
        frame = np.ascontiguousarray(frame, dtype=np.uint8)
        if not self.mp4:
            from PIL import Image

            self._gif.append(Image.fromarray(frame).quantize(colors=128))
        else:
            if self._encoder is None:
                self._encoder = self._start_encoder(frame.shape)
            self._encoder.send(frame)
        self.frames += 1

    def _start_encoder(self, shape: tuple[int, ...]):
        import imageio_ffmpeg

        height, width = shape[:2]
        if width % 2 or height % 2:
            raise ValueError(f"MP4 frames need an even width and height, got {width}x{height}")
        encoder = imageio_ffmpeg.write_frames(
            str(self._tmp),
            (width, height),
            fps=self.fps,
            codec="libx264",
            macro_block_size=1,
            output_params=["-f", "mp4"],
        )
        encoder.send(None)
        return encoder

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        try:
            if self._encoder is not None:
                self._encoder.close()
            if kind is None and self.frames == 0:
                raise ValueError(f"no frames were given for {self.path}")
            if kind is None and self._gif:
                first, *rest = self._gif
                duration = round(1000 / self.fps)
                first.save(self._tmp, save_all=True, append_images=rest, duration=duration, loop=0)
            if kind is None:
                os.replace(self._tmp, self.path)
        finally:
            self._tmp.unlink(missing_ok=True)
