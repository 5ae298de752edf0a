"""Plug-in instruction modules (TLMs) (issue 4)."""
