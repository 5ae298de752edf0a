"""The ladder language, its compiler and the scan engine (issue 3)."""
