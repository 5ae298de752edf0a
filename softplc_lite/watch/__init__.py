"""``softplc watch``: a running PLC's online view in the terminal."""
