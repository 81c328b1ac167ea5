"""``python -m vemwear``: the command-line interface."""

from vemwear.cli.main import entry

entry()
