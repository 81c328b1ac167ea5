"""Command line: ``vemwear run``, ``check``, ``schema``, ``example``, ``mesh``, ...

The configuration format is :mod:`vemwear.config` (documented in ``docs/config.md``).
"""

from ..post.outputs import write_outputs
from .output import OutputDirError, atomic_output_dir, check_output_dir

__all__ = ["OutputDirError", "atomic_output_dir", "check_output_dir", "write_outputs"]
