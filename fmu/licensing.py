"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/licensing.py."""

from fmu.build.licensing import (
    COPYRIGHT,
    LICENSE_MEMBER,
    PLATFORM_NOTICES,
    RULE,
    SPDX,
    archive_license,
    license_attribute,
    package_license,
)

__all__ = [
    "COPYRIGHT",
    "LICENSE_MEMBER",
    "PLATFORM_NOTICES",
    "RULE",
    "SPDX",
    "archive_license",
    "license_attribute",
    "package_license",
]
