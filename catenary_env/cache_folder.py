"""The user's cache folder of catenary-env: the uplift calibrations (:mod:`~catenary_env.calibration_cache`)
and the memo of the simulator's fingerprint (:mod:`~catenary_env.fingerprint`).

``CATENARY_ENV_CACHE`` sets the folder; ``CATENARY_ENV_CACHE=off`` keeps nothing on disk (the tests run
so). Default: ``$XDG_CACHE_HOME/catenary-env``, else ``~/.cache/catenary-env``.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["CACHE_ENV", "cache_folder"]

CACHE_ENV = "CATENARY_ENV_CACHE"
"""Environment variable: the cache folder, or ``off`` to keep no cache on disk."""


def cache_folder() -> Path | None:
    """The cache folder, or None when ``CATENARY_ENV_CACHE=off``."""
    chosen = os.environ.get(CACHE_ENV, "").strip()
    if chosen.lower() in ("off", "none", "0", "false"):
        return None
    if chosen:
        return Path(chosen).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "").strip() or Path.home() / ".cache"
    return Path(base) / "catenary-env"
