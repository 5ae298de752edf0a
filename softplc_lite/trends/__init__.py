"""Trends: the values of chosen addresses over time, drawn in the watch
view, recorded to CSV and VCD (docs/trends.md)."""
