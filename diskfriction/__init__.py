"""diskfriction: bifurcation and continuation analysis of frictional disks on a substrate.

The repository keeps each part in a top-level folder (scenes/, symbolic/, continuation/,
dynamics/, reports/, cli/); the install maps them into this package (setup.py), so they are
imported as ``diskfriction.<folder>`` and no generic top-level name is installed.
``diskfriction.__version__`` is looked up in the installed metadata when first asked for
(importlib.metadata costs about 30 ms, which every command would otherwise pay at start).
"""


def __getattr__(name: str):
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("diskfriction")
        except PackageNotFoundError:  # running from a checkout that was never installed
            return "0+unknown"
    raise AttributeError(f"module 'diskfriction' has no attribute {name!r}")
