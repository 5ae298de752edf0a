"""softplc_lite: a soft PLC in Python.

Ladder logic as text, run scan by scan against an emulated PLC-5/SoftPLC data
table, with COMGENIUS serial instructions loaded as a plug-in module.
"""

__version__ = "0.1.0"
