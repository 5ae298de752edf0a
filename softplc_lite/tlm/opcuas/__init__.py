"""OPCUAS: an OPC UA server over the data table and the program's symbols,
for SCADA and IIoT platforms (docs/opcuas.md). A plug-in module (TLM)
registered like MODBTCPS and ENIPS; the server is the network-server
layer's (softplc_lite/netserver), in a process of its own, with asyncua
serving OPC UA (asyncua_glue.py, the one module that imports it, with the
patches of its classes in asyncua_patches.py)."""

from .module import OpcUaServer

__all__ = ["OpcUaServer"]
