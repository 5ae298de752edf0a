"""The COMGENIUS TLM: format engine and serial instructions (issues 4 and 5)."""

from .module import ComGenius

__all__ = ["ComGenius"]
