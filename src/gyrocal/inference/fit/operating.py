"""The uplink at the campaign's rates. An onboard correction (paper eq. 3, `gyrocal.model.correction`)
is linear in each channel's rate: one scale factor a direction. Where the model lets the scale factor
change with the rate (an effect with `gyrocal.model.effects.Effect.operating_scale`, e.g.
`sf_nonlinearity`), the scale factor to uplink is the one at the rates the campaign turned: each
direction's ``sf`` plus the effect's change of the channel's increments over the angle turned that way,
which leaves every rotation's end error as the model explains it. Away from those rates the linear
correction is off by the effect's change between them. The change is linear in the effect's
parameters (`operating_map`), so the uplinked scale factors' posterior is the draws' image under it
(`gyrocal.criticism.uplinked`)."""

import numpy as np

from gyrocal.inference.errormodel import effect_regressors
from gyrocal.model import channels as ch
from gyrocal.model.channels import MOVING_RATE_FRACTION

__all__ = ["operating_map", "operating_params", "operating_shift"]


def _operating(spec) -> np.ndarray:
    """Which of ``spec``'s extra parameters belong to an operating-scale effect."""
    return np.array([bool(getattr(spec.effect(p.effect), "operating_scale", False)) for p in spec.extras], dtype=bool)


def operating_map(maneuvers, spec, biases=None) -> np.ndarray:
    """(2, n_channels, E): what each extra parameter (`ModelSpec.extras` order, per unit SI) of an
    operating-scale effect adds to ``sf_pos`` (row 0) and ``sf_neg`` (row 1): its change of each
    channel's increments over the angle the channel turned that way, over the intervals where it turns
    (its bias-free rate beyond `MOVING_RATE_FRACTION` of the maneuver's peak, so that holds, their noise
    and the bias weigh next to nothing), each direction read off the bias-free rate as the correction
    applies it (``biases``: per maneuver, rad/s; none: zero). A symmetric model (one ``sf`` a channel)
    takes the change over the angle turned either way in both rows. Zero for every other parameter."""
    n, wanted = len(spec.channels), _operating(spec)
    change, angle = np.zeros((2, n, len(wanted))), np.zeros((2, n))
    if not wanted.any():
        return change
    for m, data in enumerate(maneuvers):
        gyro = effect_regressors(data, spec)[0][:, :, wanted]
        bias = np.zeros(n) if biases is None else np.asarray(biases[m], dtype=float).reshape(n)
        turned = np.asarray(data.increments, dtype=float) - np.outer(data.dt, bias)
        rate = np.abs(turned) / np.asarray(data.dt, dtype=float)[:, None]
        moving = rate > MOVING_RATE_FRACTION * rate.max()
        for row, way in enumerate((moving & (turned > 0), moving & (turned < 0))):
            change[row][:, wanted] += np.sum(np.where(way[:, :, None], gyro, 0.0), axis=0)
            angle[row] += np.sum(np.where(way, turned, 0.0), axis=0)
    if any(p.name == "sf" for p in spec.parameters[spec.core]):
        change = np.broadcast_to(change[0] - change[1], change.shape)
        angle = np.broadcast_to(angle[0] - angle[1], angle.shape)
    return np.divide(change, angle[:, :, None], out=np.zeros(change.shape), where=angle[:, :, None] != 0)


def operating_shift(maneuvers, spec, extras_si, biases=None) -> np.ndarray:
    """(2, n_channels): what the operating-scale effects at ``extras_si`` (`ModelSpec.extras` order, SI)
    add to ``sf_pos`` (row 0) and ``sf_neg`` (row 1), `operating_map` applied; zero without such an effect."""
    return operating_map(maneuvers, spec, biases) @ np.asarray(extras_si, dtype=float)


def operating_params(params: ch.ChannelParams, shift: np.ndarray) -> ch.ChannelParams:
    """``params`` with `operating_shift`'s ``shift`` added to their scale factors."""
    return ch.ChannelParams(params.channels, params.sf_pos + shift[0], params.sf_neg + shift[1], params.mis_rad,
                            params.bias_rad_s)
