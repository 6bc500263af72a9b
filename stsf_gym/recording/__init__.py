"""Episodes recorded for the tools robotics people use, and estimators replayed on logs.

- :class:`~stsf_gym.recording.wrapper.RecordEpisode`: a wrapper writing each episode as an MCAP
  log of standard ROS 2 messages (:mod:`.topics`, :mod:`.mcap_writer`) or a Rerun recording
  (:mod:`.rerun_writer`).
- :func:`~stsf_gym.recording.log_reader.read_log` and :func:`~stsf_gym.recording.replay.replay`:
  any pose source rerun on a log, with no simulator (docs/log_format.md: a log of your own
  robot).
"""

from __future__ import annotations

import importlib.util

from stsf_gym.validation import ConfigError

#: The modules of the ``record`` extra (``pip install 'stsf-gym[record]'``).
EXTRA_MODULES = ("mcap", "rosbags", "rerun")


def missing_modules() -> list[str]:
    """The ``record`` extra's modules that are not installed here."""
    return [name for name in EXTRA_MODULES if importlib.util.find_spec(name) is None]


def require_recording(what: str) -> None:
    """Raise :class:`ConfigError` when ``what`` (``--record mcap``, ``replay``) cannot run:
    the ``record`` extra is not installed."""
    missing = missing_modules()
    if missing:
        raise ConfigError(
            f"{what} needs the recording extra ({', '.join(missing)} not installed): "
            "pip install 'stsf-gym[record]'"
        )
