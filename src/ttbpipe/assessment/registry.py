"""The registry of assessment profiles by name.

Every module of this package that defines ``PROFILE`` (a :class:`~.base.Profile`) is a profile,
found by name: a new standard is a new module (with its test), nothing else to register.
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import lru_cache

from .base import Profile


@lru_cache(maxsize=1)
def profiles() -> dict[str, Profile]:
    """{name: profile} of every module of the package that defines ``PROFILE``."""
    from . import __path__ as package_path

    found: dict[str, Profile] = {}
    for info in sorted(pkgutil.iter_modules(package_path), key=lambda m: m.name):
        module = importlib.import_module(f"{__package__}.{info.name}")
        profile = getattr(module, "PROFILE", None)
        if isinstance(profile, Profile):
            if profile.name in found:
                raise RuntimeError(f"two assessment profiles are named {profile.name!r}")
            found[profile.name] = profile
    return found


def get_profile(name: str) -> Profile:
    """The profile called ``name``; ValueError naming the known ones otherwise."""
    known = profiles()
    if name not in known:
        raise ValueError(f"unknown assessment standard {name!r}; known: {sorted(known)}")
    return known[name]
