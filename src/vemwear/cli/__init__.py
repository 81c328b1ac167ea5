"""Command line: ``vemwear run``, ``check``, ``schema``, ``example``, ``mesh``, ...

Argument parsing, printing and exit codes only; the work is done by the library
(:mod:`vemwear.runner` runs a configuration). The configuration format is
:mod:`vemwear.config` (documented in ``docs/config.md``).
"""
