"""Error classes of regopack.

Every error a user can cause derives from :class:`RegopackError`; the command
line prints such errors as one line without a traceback.
"""

from __future__ import annotations


class RegopackError(Exception):
    """Base class of all errors that describe a user mistake or a bad input."""


class ConfigError(RegopackError):
    """A scene or command-line value is missing, malformed or out of range."""


class PluginError(RegopackError):
    """A plugin is unknown, registered twice, or does not honour its contract."""


class PackingFileError(RegopackError):
    """A packing file cannot be read, breaks the packing format, or has an unsupported version."""


class PackingError(RegopackError, ValueError):
    """A packing's arrays break the packing format (a shape, dtype, range or order)."""


class GeometryError(RegopackError):
    """A particle or domain geometry is invalid (e.g. a particle does not fit the domain)."""


class ExportError(RegopackError):
    """A packing cannot be exported, or an exported file cannot be read back."""


class DeprecatedNameWarning(FutureWarning):
    """An old name of a plugin (e.g. the analyzer ``contacts3d``) was used; it goes next release.

    A :class:`FutureWarning`, which Python shows by default, because such names
    come from what users write (scenes, options, calls); the command line
    prints it as one ``regopack: warning:`` line.
    """


class DensityTargetWarning(UserWarning):
    """A density target was not met within its tolerance; the closest packing was kept."""


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM (what batch schedulers send at a time limit).

    The command line turns SIGTERM into this exception, a kind of
    :class:`KeyboardInterrupt`, so that a terminated run cleans up exactly like
    one interrupted with Ctrl-C; it then exits with status 143.
    """
