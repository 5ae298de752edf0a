"""The emulated PLC-5/SoftPLC data table (see docs/datatable.md)."""

from .address import Address, ValueKind, parse_address
from .errors import (
    AddressError,
    AddressRangeError,
    BlockRangeError,
    DataTableError,
    SnapshotError,
    ValueRangeError,
)
from .files import DataFile
from .filetypes import FILE_TYPES, MAX_ELEMENTS, STRING_CHARS, FileType
from .table import DataTable, Location, WordBlock, bit_mask, data_bit_mask, item_bit_mask, to_signed

__all__ = [
    "Address", "AddressError", "AddressRangeError", "BlockRangeError", "DataFile",
    "DataTable", "DataTableError", "FILE_TYPES", "FileType", "Location", "MAX_ELEMENTS",
    "STRING_CHARS", "SnapshotError", "ValueKind", "ValueRangeError", "WordBlock",
    "bit_mask", "data_bit_mask", "item_bit_mask", "parse_address", "to_signed",
]
