"""Two-point support in motion: the turned stack and the inchworm walk."""
