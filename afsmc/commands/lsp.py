"""`afsmc lsp`: the language server, speaking LSP over standard input and output."""

from __future__ import annotations

import argparse


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--stdio", action="store_true",
                   help="use standard input/output (the default and only transport; accepted "
                        "because some editors pass it)")


def run(args: argparse.Namespace) -> int:
    from afsmc.lsp.server import serve  # pygls is only imported when the server runs

    return serve()
