"""Exceptions that carry enough context for one clear line to the user.

The CLI maps :class:`InputError` (and subclasses) to exit status 2 and
everything else derived from :class:`BifilarError` to exit status 1.
"""

from __future__ import annotations


class BifilarError(Exception):
    """Base class of every error the package raises on purpose."""


class InputError(BifilarError):
    """Invalid input: a config field, a command-line argument, a data file.

    Parameters
    ----------
    field : str
        Dotted path of the offending field (``rig.lengths.1``) or the
        argument name (``--amplitude``).
    message : str
        What is wrong and what was expected.
    """

    def __init__(self, field: str, message: str):
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}" if field else message)


class ConfigErrors(InputError):
    """Several :class:`InputError` found in one pass over a config."""

    def __init__(self, errors: list[InputError]):
        self.errors = list(errors)
        first = self.errors[0]
        super().__init__(first.field, first.message)

    def __str__(self) -> str:  # one line per problem
        return "\n".join(str(e) for e in self.errors)


class SlackWireError(InputError):
    """The scene cannot hang with every wire taut (a physical impossibility
    of the input, hence exit status 2).  ``wires`` are 1-based indices.

    ``advise``: optional callable returning the full message with the
    advice (how much to shorten each wire, checked by solving the changed
    rig); it is called on first use of the message (``str``, ``.message``),
    so callers that catch and drop the error (finite-difference neighbours,
    sweep points) do not pay for it.  If it fails, ``message`` stands.
    ``gaps``: how far each of ``wires`` is from straight at rest (m; 0 for
    a straight wire without load), where known.
    """

    def __init__(self, wires: list[int], message: str, advise=None, gaps=None):
        self.wires = list(wires)
        self.gaps = None if gaps is None else [float(g) for g in gaps]
        self._advise = advise
        super().__init__("rig.lengths", message)

    @property
    def message(self) -> str:
        if self._advise is not None:
            advise, self._advise = self._advise, None
            try:
                self._message = advise()
            except Exception:  # noqa: BLE001 - the plain message is still right
                pass
            self.args = (f"{self.field}: {self._message}",)
        return self._message

    @message.setter
    def message(self, value: str) -> None:
        self._message = value

    def __str__(self) -> str:
        self.message  # noqa: B018 - computes the advice once
        return super().__str__()

    def __reduce__(self):  # picklable (sweep workers), with the advice computed
        return (type(self), (self.wires, self.message, None, self.gaps))


class StiffnessNeededError(SlackWireError):
    """A rig of 4 or 5 nearly dependent wires that the rigid model would
    refuse (a wire slack by less than a loaded wire's stretch, or pushing),
    where the split, and whether any wire is slack, is set by the wires'
    stretch: the field to give is ``rig.stiffness`` (docs/design.md
    "elastic, session 15").  Same arguments as :class:`SlackWireError`."""

    def __init__(self, wires: list[int], message: str, advise=None, gaps=None):
        super().__init__(wires, message, advise, gaps)
        self.field = "rig.stiffness"
        self.args = (f"{self.field}: {message}",)


class UnstableRestError(InputError):
    """The rest pose exists but a mode has negative stiffness."""


class SingularCoordinatesError(BifilarError, ArithmeticError):
    """A coordinate chart (the thesis's angles) is singular at this pose."""


class ConvergenceError(BifilarError):
    """An iterative solver did not converge (rest pose, inversion, ...)."""


class IntegrationError(BifilarError):
    """The time integrator failed or a health tolerance was blown."""


class NotApplicable(Exception):
    """A method (a rung of the estimator ladder, a coordinate chart) does not
    apply to this scene or mode; the message says why.  Not an error of the
    input: callers report it beside the methods that do apply."""


def one_line(exc: BaseException) -> str:
    """The first line of an exception's message (of its first error, with
    "(+N more)", for an exception carrying ``errors``), or its type's name
    where the message is empty: how a sweep point's refusal is worded."""
    errs = getattr(exc, "errors", None)
    if errs:
        more = f" (+{len(errs) - 1} more)" if len(errs) > 1 else ""
        return str(errs[0]).splitlines()[0] + more
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
