"""Pose estimators: odometry, conventional fusion, STSF and EKF (one interface)."""
