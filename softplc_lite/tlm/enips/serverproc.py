"""The ENIPS server process (``python -m softplc_lite.tlm.enips.serverproc
OUT_FD IMAGE_FD``): the network-server layer's process (netserver/process.py),
under a name that says whose it is; handler.py serves the requests."""

from ...netserver.process import run_and_exit

if __name__ == "__main__":
    run_and_exit()
