"""The library's exception family: every error it raises derives from :class:`WbcError`."""


class WbcError(Exception):
    """Base class of every error raised by this library."""


class ConfigurationError(WbcError, ValueError):
    """A parameter, argument or array has an invalid value, type or shape."""


class DescriptionNotFoundError(WbcError, FileNotFoundError):
    """The GO2 robot description (URDF/SRDF) could not be found on this machine."""


class UnknownNameError(WbcError, KeyError):
    """A joint, foot, frame, pose or backend name that does not exist.

    The message lists every valid name.
    """

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable.
        return str(self.args[0]) if self.args else ""


class ReachabilityError(ConfigurationError):
    """A target lies outside the robot's reachable range."""


class NonFiniteError(ConfigurationError):
    """A NaN or infinite value in a state, reference or parameter."""


class OrderMismatchError(ConfigurationError):
    """A record or command in one joint or leg order handed where another is expected.

    The message names both orders and the conversion to use.
    """
