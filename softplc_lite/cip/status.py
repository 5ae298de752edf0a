"""CIP general status codes, as the CIP specification names them (Volume 1,
Appendix B "Status Codes"; the same table in Rockwell's 1756-PM020,
"Logix5000 Data Access", CIP General Status). A reply's general status is
one byte; some codes carry additional (extended) status words."""

SUCCESS = 0x00
CONNECTION_FAILURE = 0x01
RESOURCE_UNAVAILABLE = 0x02
INVALID_PARAMETER_VALUE = 0x03
PATH_SEGMENT_ERROR = 0x04
PATH_DESTINATION_UNKNOWN = 0x05
PARTIAL_TRANSFER = 0x06
CONNECTION_LOST = 0x07
SERVICE_NOT_SUPPORTED = 0x08
INVALID_ATTRIBUTE_VALUE = 0x09
ATTRIBUTE_LIST_ERROR = 0x0A
ALREADY_IN_REQUESTED_MODE = 0x0B
OBJECT_STATE_CONFLICT = 0x0C
OBJECT_ALREADY_EXISTS = 0x0D
ATTRIBUTE_NOT_SETTABLE = 0x0E
PRIVILEGE_VIOLATION = 0x0F
DEVICE_STATE_CONFLICT = 0x10
REPLY_DATA_TOO_LARGE = 0x11
FRAGMENTATION_OF_PRIMITIVE = 0x12
NOT_ENOUGH_DATA = 0x13
ATTRIBUTE_NOT_SUPPORTED = 0x14
TOO_MUCH_DATA = 0x15
OBJECT_DOES_NOT_EXIST = 0x16
INVALID_PARAMETER = 0x20
EMBEDDED_SERVICE_ERROR = 0x1E  # a service of a Multiple Service Packet failed
PATH_SIZE_INVALID = 0x26
GENERAL_ERROR = 0xFF  # Logix's general error: the extended status word says what (1756-PM020)

NAMES = {value: name.replace("_", " ").lower() for name, value in globals().items()
         if name.isupper() and isinstance(value, int)}


def describe(status: int) -> str:
    """``0x05 (path destination unknown)``: a status as logs and errors show it."""
    return f"0x{status:02X} ({NAMES.get(status, 'unknown status')})"
