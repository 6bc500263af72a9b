"""Rendering: the scene description, the camera's OpenGL renderer, the top-down map and the
human window."""
