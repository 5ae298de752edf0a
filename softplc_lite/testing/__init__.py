"""Tests for ladder programs: scenario files, their runner and a Python API."""
