"""Command line and configuration files.

``vemwear run CONFIG.toml -o OUTDIR``, ``vemwear check CONFIG.toml`` and
``vemwear example 5.2 -o OUTDIR``; the configuration format is documented in
``docs/config.md``.
"""

from .config import Config, ConfigError, OutputOptions, build_mesh, load_config, parse_config
from .output import OutputDirError, atomic_output_dir, check_output_dir, write_outputs

__all__ = [
    "Config",
    "ConfigError",
    "OutputDirError",
    "OutputOptions",
    "atomic_output_dir",
    "build_mesh",
    "check_output_dir",
    "load_config",
    "parse_config",
    "write_outputs",
]
