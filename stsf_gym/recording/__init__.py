"""Episodes recorded for the tools robotics people use, and estimators replayed on logs.

- :class:`~stsf_gym.recording.wrapper.RecordEpisode`: a wrapper writing each episode as an MCAP
  log of standard ROS 2 messages (:mod:`.topics`, :mod:`.mcap_writer`) or a Rerun recording
  (:mod:`.rerun_writer`).
- :func:`~stsf_gym.recording.log_reader.read_log` and :func:`~stsf_gym.recording.replay.replay`:
  any pose source rerun on a log, with no simulator (docs/log_format.md: a log of your own
  robot).
"""
