"""CIP and EtherNet/IP as bytes: the codec the ENIPS module serves with
(status codes, messages), knowing nothing of the data table or the runtime."""
