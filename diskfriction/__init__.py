"""diskfriction: bifurcation and continuation analysis of frictional disks on a substrate.

The repository keeps each part in a top-level folder (scenes/, symbolic/, continuation/,
dynamics/, reports/, cli/); the install maps them into this package (setup.py), so they are
imported as ``diskfriction.<folder>`` and no generic top-level name is installed.
"""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("diskfriction")
except PackageNotFoundError:  # running from a checkout that was never installed
    __version__ = "0+unknown"
