"""One kind of check: a `Finding` says what was checked, the figure against its threshold, whether
it passes, warns or refuses, and what to do. Input checks, residual diagnostics, model choice and
the verdict all speak in findings; the report renders them and decides nothing."""

from dataclasses import asdict, dataclass, field
from enum import Enum

__all__ = ["Finding", "Findings", "Status", "refusals", "warnings"]


class Status(str, Enum):
    """How a finding weighs: ``pass``, ``warn`` (recorded, the run goes on) or ``refuse`` (no
    verdict of GO: bad input stops the run, a failed verdict check makes it NO-GO)."""

    PASS = "pass"
    WARN = "warn"
    REFUSE = "refuse"


@dataclass(frozen=True)
class Finding:
    """What one check found."""

    check: str
    """What was checked, in a few words (``converged``, ``clock offset``)."""
    status: Status
    why: str
    """What was found, in a sentence a reviewer can act on."""
    figure: float | None = None
    """The measured figure, where the check compares one with a threshold."""
    threshold: float | None = None
    unit: str = ""
    """The unit of ``figure`` and ``threshold``."""
    action: str = ""
    """What to do about it, where the check knows."""
    where: str = ""
    """The maneuver, channel, file or line it concerns ("" for the whole campaign)."""

    @property
    def passed(self) -> bool:
        return self.status is not Status.REFUSE

    @classmethod
    def judged(cls, check: str, passed: bool, why: str, **details) -> "Finding":
        """A verdict check: it passes or refuses."""
        return cls(check, Status.PASS if passed else Status.REFUSE, why, **details)

    def as_check(self) -> dict:
        """The ``{check, passed, why}`` record of ``verdict.json`` and ``diagnostics.json``
        (docs/interface.md section 5)."""
        return {"check": self.check, "passed": self.passed, "why": self.why}

    def as_dict(self) -> dict:
        """Every field, the status as its word."""
        return {**asdict(self), "status": self.status.value}


def refusals(findings) -> list:
    """The findings that refuse."""
    return [f for f in findings if f.status is Status.REFUSE]


def warnings(findings) -> list:
    """The findings that warn."""
    return [f for f in findings if f.status is Status.WARN]


@dataclass
class Findings:
    """What the input checks found about one campaign: refusals stop it before any fit; warnings,
    the outliers left out and the mounting applied are recorded in ``input.json``."""

    items: list = field(default_factory=list)
    """The `Finding` of every check that refused or warned, in the order they were made."""
    outliers: list = field(default_factory=list)
    mounting: dict = field(default_factory=dict)
    """The reference's mounting applied (`gyrocal.checks.mounting.align`): quaternion, source and angle."""

    def refuse(self, check: str, why: str, **details):
        self.items.append(Finding(check, Status.REFUSE, why, **details))

    def warn(self, check: str, why: str, **details):
        self.items.append(Finding(check, Status.WARN, why, **details))

    @property
    def errors(self) -> list:
        """What refuses the campaign, in words."""
        return [f.why for f in refusals(self.items)]

    @property
    def warnings(self) -> list:
        """What was recorded as a warning, in words."""
        return [f.why for f in warnings(self.items)]
