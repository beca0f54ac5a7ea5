"""The gyro channel model of docs/interface.md section 2 (the paper's eq. 3, per channel).

For channel c with input axis a::

    omega_c = (1 + s_c) * (omega_a + sum_b m_cb * omega_b) + b_c

with ``s_c = sf_pos`` when the rate the channel senses, ``omega_a + sum_b m_cb * omega_b``, is
positive and ``sf_neg`` when it is negative (a symmetric model's one ``sf`` is both): the branch
follows the channel's own output, which is all the onboard correction sees (`correction`) and all
the inverse (`solve_body`) can use. Everything here is in SI: scale factors dimensionless,
misalignments in rad, bias in rad/s. The same relations hold for increments over an interval ``dt``.
"""

from dataclasses import dataclass, field

import numpy as np

from gyrocal.model.units import AXES, AXIS_INDEX

__all__ = [
    "MOM_CHANNELS", "MOVING_RATE_FRACTION", "SYMBOLS", "Channel", "ChannelParams", "channel_sets", "input_axes",
    "measure", "response_rows", "solve_body"
]

MOVING_RATE_FRACTION = 0.05
"""A gyro sample counts as turning while its rate exceeds this share of the maneuver's peak;
below it, a maneuver is holding inertial (the paper's holds before and after a rotation)."""


@dataclass(frozen=True)
class Channel:
    """One sensing axis of a gyro: of a two-axis DTG (``dtg<N>_<axis>``, ``dtg`` its number) or of
    any other gyro (``dtg`` None)."""

    name: str
    dtg: int | None
    axis: str

    def __post_init__(self):
        if self.axis not in AXIS_INDEX:
            raise ValueError(f"channel {self.name}: axis must be one of {AXES}, got {self.axis!r}")

    @property
    def axis_index(self) -> int:
        return AXIS_INDEX[self.axis]

    @property
    def other_axes(self) -> tuple:
        """The two axes a channel can be misaligned toward, in body-axis order."""
        return tuple(a for a in AXES if a != self.axis)


MOM_CHANNELS = (
    Channel("dtg1_roll", 1, "roll"),
    Channel("dtg1_pitch", 1, "pitch"),
    Channel("dtg2_yaw", 2, "yaw"),
    Channel("dtg2_pitch", 2, "pitch"),
    Channel("dtg3_yaw", 3, "yaw"),
    Channel("dtg3_roll", 3, "roll"),
)
"""The Mars Orbiter Mission arrangement: DTG1 roll+pitch, DTG2 yaw+pitch, DTG3 yaw+roll."""

SYMBOLS = {"sf_pos": ("sf_pos", None), "sf_neg": ("sf_neg", None), "sf": (("sf_pos", "sf_neg"), None),
           **{f"mis_{b}": ("mis_rad", i) for i, b in enumerate(AXES)}}
"""Eq. 3's terms by their contract names: ``mis_<b>`` is the misalignment toward axis b; ``sf``
(the symmetric model's) is one scale factor for both branches, ``sf_pos = sf_neg = sf``."""


@dataclass
class ChannelParams:
    """Residual scale factors, misalignments and biases of a list of channels (SI)."""

    channels: tuple
    sf_pos: np.ndarray
    sf_neg: np.ndarray
    mis_rad: np.ndarray
    """(n, 3): misalignment of channel i toward each body axis; own axis is zero."""
    bias_rad_s: np.ndarray = field(default=None)

    def __post_init__(self):
        n = len(self.channels)
        self.channels = tuple(self.channels)
        self.sf_pos = np.asarray(self.sf_pos, dtype=float).reshape(n)
        self.sf_neg = np.asarray(self.sf_neg, dtype=float).reshape(n)
        self.mis_rad = np.asarray(self.mis_rad, dtype=float).reshape(n, 3).copy()
        self.mis_rad[np.arange(n), [c.axis_index for c in self.channels]] = 0.0
        self.bias_rad_s = (np.zeros(n) if self.bias_rad_s is None
                           else np.asarray(self.bias_rad_s, dtype=float).reshape(n))

    @classmethod
    def zeros(cls, channels):
        n = len(channels)
        return cls(channels, np.zeros(n), np.zeros(n), np.zeros((n, 3)), np.zeros(n))

    def get(self, i: int, name: str) -> float:
        """Channel i's term ``name`` (a `SYMBOLS` key), SI."""
        field_name, column = SYMBOLS[name]
        if isinstance(field_name, tuple):  # "sf": the branches' mean (equal where the model is symmetric)
            return float(np.mean([self.get(i, f) for f in field_name]))
        values = getattr(self, field_name)
        return float(values[i] if column is None else values[i, column])

    def set(self, i: int, name: str, value: float):
        field_name, column = SYMBOLS[name]
        for f in field_name if isinstance(field_name, tuple) else (field_name,):
            values = getattr(self, f)
            if column is None:
                values[i] = value
            else:
                values[i, column] = value

    def subset(self, names):
        """The parameters of the named channels, in the given order."""
        index = {c.name: i for i, c in enumerate(self.channels)}
        idx = [index[n] for n in names]
        return ChannelParams(tuple(self.channels[i] for i in idx), self.sf_pos[idx],
                             self.sf_neg[idx], self.mis_rad[idx], self.bias_rad_s[idx])


def input_axes(channels) -> np.ndarray:
    """Index of each channel's nominal input axis."""
    return np.array([c.axis_index for c in channels], dtype=int)


def response_rows(params: ChannelParams) -> np.ndarray:
    """(n, 3) rows ``e_a + m_c``: what each channel senses of the body rate, before scale."""
    rows = params.mis_rad.copy()
    rows[np.arange(len(params.channels)), input_axes(params.channels)] = 1.0
    return rows


def measure(body: np.ndarray, params: ChannelParams, dt_s=None, extra_scale=None) -> np.ndarray:
    """Forward model: body rates (or increments over ``dt_s``) to every channel's output.

    ``body`` is (N, 3); returns (N, n_channels). With ``dt_s`` the bias is integrated.
    ``extra_scale`` (N, n_channels) adds a sample-dependent scale-factor term, such as
    a rate-squared nonlinearity or a temperature coefficient (the simulator's effects).
    """
    body = np.atleast_2d(np.asarray(body, dtype=float))
    sensed = body @ response_rows(params).T
    positive = sensed > 0
    scale = 1.0 + np.where(positive, params.sf_pos, params.sf_neg)
    if extra_scale is not None:
        scale = scale + extra_scale
    bias = params.bias_rad_s if dt_s is None else np.outer(np.asarray(dt_s, dtype=float), params.bias_rad_s)
    return scale * sensed + bias


def solve_body(outputs: np.ndarray, params: ChannelParams, dt_s=None) -> np.ndarray:
    """Inverse model: outputs of channels that span the three axes back to body rates.

    Works for any set of three or more channels covering roll, pitch and yaw (the
    in-loop set or a redundant one); with more than three it is least squares.
    The scale-factor branch of each channel follows the sign of its bias-free output.
    """
    outputs = np.atleast_2d(np.asarray(outputs, dtype=float))
    axes = input_axes(params.channels)
    if set(axes.tolist()) != {0, 1, 2}:
        missing = [AXES[a] for a in range(3) if a not in axes]
        raise ValueError(f"channels {[c.name for c in params.channels]} do not span the body "
                         f"axes: no channel senses {', '.join(missing)}")
    bias = params.bias_rad_s if dt_s is None else np.outer(np.asarray(dt_s, dtype=float), params.bias_rad_s)
    unbiased = outputs - bias
    positive = unbiased > 0
    rows = response_rows(params)
    n = len(params.channels)
    pattern = positive @ (1 << np.arange(n))
    body = np.empty((len(outputs), 3))
    for code in np.unique(pattern):
        signs = (int(code) >> np.arange(n)) & 1
        scale = 1.0 + np.where(signs == 1, params.sf_pos, params.sf_neg)
        gain = scale[:, None] * rows
        sel = pattern == code
        body[sel] = unbiased[sel] @ np.linalg.pinv(gain).T
    return body


def channel_sets(channels, in_loop=None) -> list:
    """Channel sets that together see every channel, each spanning the three axes.

    The first set is ``in_loop`` (or the first channel of each axis); set k takes the
    k-th channel of each axis, so the sets share no channel.
    Each set is a tuple of names ordered roll, pitch, yaw.
    """
    by_axis = {a: [c.name for c in channels if c.axis == a] for a in AXES}
    missing = [a for a, names in by_axis.items() if not names]
    if missing:
        raise ValueError(f"no gyro channel senses {', '.join(missing)}: cannot propagate attitude")
    if in_loop:
        lookup = {c.name: c for c in channels}
        first = {lookup[n].axis: n for n in in_loop}
        for a in AXES:
            by_axis[a].remove(first[a])
            by_axis[a].insert(0, first[a])
    counts = {a: len(v) for a, v in by_axis.items()}
    if len(set(counts.values())) > 1:
        raise ValueError(
            f"every body axis needs the same number of gyro channels, got {counts}: the channel sets "
            "would share a channel, whose error the noise model cannot yet separate from the star "
            "tracker's (a known limitation; leave the unpaired channels out of campaign.yaml)")
    return [tuple(by_axis[a][k] for a in AXES) for k in range(counts["roll"])]
