"""The robot's sensors: the camera (rendered through lens and image sensor, or the fast mode's
simulated detections) with its timing, the sonar ring with its beam model and firing order, and
the wheel encoders."""
