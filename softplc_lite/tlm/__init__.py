"""Plug-in instruction modules (TLMs): the door third-party packages and
COMGENIUS use alike. See api.py for what a module implements and
registry.py for how it is found and enabled."""

from .api import TLM, BoundOperand, ControlElement, ControlledInstruction, InstructionContext
from .errors import ModuleError
from .registry import GROUP, MODULES_FILE, instruction_set, installed, load_module, load_modules

__all__ = [
    "GROUP", "MODULES_FILE", "TLM", "BoundOperand", "ControlElement", "ControlledInstruction",
    "InstructionContext", "ModuleError", "installed", "instruction_set", "load_module", "load_modules",
]
