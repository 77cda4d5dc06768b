"""The package's version: the installed distribution's, else the checkout's."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("quickreturn-synth")
except PackageNotFoundError:  # run from a checkout without installing
    __version__ = "0.1.0"
