"""``softplc opcua-cert``: make the OPC UA server's certificate and key
(docs/opcuas.md, "Security")."""

from __future__ import annotations

import argparse
import sys

from ..tlm.opcuas.security import DAYS, CertPaths, application_uri, create_certificate
from .common import EXIT_ERROR, EXIT_OK, app_directory, int_in

NAME = "opcua-cert"


def add_parser(sub) -> argparse.ArgumentParser:
    c = sub.add_parser(NAME, help="make the OPC UA server's self-signed certificate and key",
                       description="Make the OPC UA server's self-signed application instance certificate and its "
                                   "private key in APP/OPCUAS.PKI/ (docs/opcuas.md, \"Security\").",
                       epilog="example: softplc opcua-cert programs/tank")
    c.add_argument("app", metavar="APP", help="the app's directory")
    c.add_argument("--uri", help="the ApplicationUri (default urn:HOST:softplc_lite:APPNAME)")
    c.add_argument("--hostname", help="the host name in the certificate (default this host's)")
    c.add_argument("--days", type=int_in(range(1, 36525), "days"), default=DAYS,
                   help=f"how long the certificate is valid (default {DAYS})")
    c.add_argument("--force", action="store_true",
                   help="replace a certificate already there (clients that trust it must trust the new one)")
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    app = app_directory(args.app)
    if app is None:
        return EXIT_ERROR
    paths = CertPaths.for_app(app)
    if (paths.cert.exists() or paths.key.exists()) and not args.force:
        print(f"error: {paths.cert.parent}: a certificate is there already; --force replaces it "
              "(every client that trusts it must then trust the new one)", file=sys.stderr)
        return EXIT_ERROR
    name = app.resolve().name
    uri = args.uri or application_uri(name, args.hostname)
    create_certificate(paths.cert, paths.key, uri, f"softplc_lite {name}", args.hostname, args.days)
    paths.trusted.mkdir(exist_ok=True)
    print(f"wrote {paths.cert} (application URI {uri}, valid {args.days} days)")
    print(f"wrote {paths.key} (mode 0600)")
    print(f"trusted client certificates go in {paths.trusted}/")
    return EXIT_OK

