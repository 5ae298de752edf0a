"""The COMGENIUS TLM: format engine and serial instructions."""

from .module import ComGenius

__all__ = ["ComGenius"]
