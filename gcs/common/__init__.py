"""Foundations every other package may use; it imports nothing of the project.

Configs are typed, frozen dataclasses validated from YAML (:func:`from_mapping`), the
shipped config files are found in a checkout or an install (:func:`shipped_config`),
and compiled kernels are built with :func:`kernel`, whose disk cache is checked
against their sources the first time one is built.

Modules:

    ``_gravity``       Standard gravity: the one value the simulator, the airframe checks and
                       the analysis share.
    ``_hold``          The gains of a hold by acceleration, shared by the loop and the PX4
                       take-off stream.
    ``_jit_cache``     Compiled kernels whose numba disk cache stays honest across files.
    ``_lazy``          Public modules of a package that load on first use, not with the
                       package.
    ``_shipped``       Where the configs shipped with the project are, in a checkout and
                       once installed.
    ``_signals``       Ctrl-C and SIGTERM stop a command, whatever started it; a child dies
                       with its parent.
    ``_threads``       Stopping a thread and saying so when it will not stop.
    ``_typed_config``  Typed, validated configuration objects built from YAML.
"""

from gcs.common._gravity import STANDARD_GRAVITY
from gcs.common._hold import HOLD_KP, HOLD_KV
from gcs.common._jit_cache import kernel
from gcs.common._lazy import lazy_modules
from gcs.common._shipped import LOCAL_CONFIGS, default_config, shipped_config
from gcs.common._signals import die_with_parent, stop_on_signals
from gcs.common._threads import join_thread
from gcs.common._typed_config import (
    ConfigError,
    FieldError,
    field,
    from_mapping,
    load_yaml,
    to_mapping,
)

__all__ = [
    "HOLD_KP",
    "HOLD_KV",
    "LOCAL_CONFIGS",
    "STANDARD_GRAVITY",
    "ConfigError",
    "FieldError",
    "default_config",
    "die_with_parent",
    "field",
    "from_mapping",
    "join_thread",
    "kernel",
    "lazy_modules",
    "load_yaml",
    "shipped_config",
    "stop_on_signals",
    "to_mapping",
]
