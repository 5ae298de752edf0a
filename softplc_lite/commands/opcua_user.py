"""``softplc opcua-user``: add, change or remove a user of the OPC UA
server, the password read without echo (docs/opcuas.md, "Security")."""

from __future__ import annotations

import argparse
import getpass
import sys

from ..tlm.opcuas.users import FILE_NAME, NAME as USER_NAME, Users
from .common import EXIT_ERROR, EXIT_OK, app_directory

NAME = "opcua-user"
MIN_PASSWORD = 8  # a choice: NIST SP 800-63B's least length for a chosen secret


def add_parser(sub) -> argparse.ArgumentParser:
    u = sub.add_parser(NAME, help="add, change or remove a user of the OPC UA server",
                       description=f"Add or change a user of the OPC UA server in APP/{FILE_NAME}, the password "
                                   "stored hashed (docs/opcuas.md, \"Security\"). The password is asked twice "
                                   "without echo on a terminal, else read as one line of standard input.",
                       epilog="example: softplc opcua-user programs/tank operator --write")
    u.add_argument("app", metavar="APP", help="the app's directory")
    u.add_argument("name", metavar="NAME", help="the user name (1 to 64 of A-Z a-z 0-9 _ . @ -)")
    rights = u.add_mutually_exclusive_group()
    rights.add_argument("--write", action="store_true", help="the user may write (default: read only)")
    rights.add_argument("--remove", action="store_true", help="remove the user")
    u.set_defaults(func=run)
    return u


def run(args: argparse.Namespace) -> int:
    app = app_directory(args.app)
    if app is None:
        return EXIT_ERROR
    if not USER_NAME.fullmatch(args.name):
        print(f"error: expected a user name of 1 to 64 letters, digits, _ . @ or -, not {args.name[:70]!r}",
              file=sys.stderr)
        return EXIT_ERROR
    path = app / FILE_NAME
    users = Users.load(path)
    if args.remove:
        if not users.remove(args.name):
            print(f"error: {path}: no user {args.name!r}", file=sys.stderr)
            return EXIT_ERROR
        users.save(path)
        print(f"removed {args.name} from {path}")
        return EXIT_OK
    password = _password()
    if password is None:
        return EXIT_ERROR
    changed = args.name in users.entries
    users.set(args.name, password, args.write)
    users.save(path)
    print(f"{'changed' if changed else 'added'} {args.name} ({'write' if args.write else 'read'}) in {path}")
    return EXIT_OK


def _password() -> str | None:
    """The password: asked twice without echo on a terminal, else one line
    of standard input (a script's pipe); None after saying what is wrong."""
    if sys.stdin.isatty():
        password = getpass.getpass("password: ")
        if getpass.getpass("again: ") != password:
            print("error: the two passwords differ", file=sys.stderr)
            return None
    else:
        password = sys.stdin.readline().rstrip("\r\n")
    if len(password) < MIN_PASSWORD:
        print(f"error: expected a password of {MIN_PASSWORD} characters or more", file=sys.stderr)
        return None
    return password
