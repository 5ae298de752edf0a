"""Logix programs: Studio 5000 exports (L5X, L5K) read, laid out over the
data table, and run by the ladder engine (docs/logix.md)."""
