"""Subcommands of the `afsmc` command line; see afsmc/cli.py."""
