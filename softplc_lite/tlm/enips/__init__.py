"""ENIPS: the EtherNet/IP server module (docs/enips.md): PCCC and CIP tag
services over the data table, on the network-server layer."""

from .module import EnipServer

__all__ = ["EnipServer"]
