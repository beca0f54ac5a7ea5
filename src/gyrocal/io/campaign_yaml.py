"""``campaign.yaml`` (docs/interface.md section 3): its channels, maneuvers and noise knowledge,
parsed and checked. The file is read by `gyrocal.io.yamlfile` (no aliases, no duplicate keys, a
bounded size) and checked against ``gyrocal/io/schemas/campaign.schema.json``, then by hand for
what a schema cannot say. Bad input is refused with a `TelemetryError` naming the file, the key
(and its line) and what is wrong."""

import itertools
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gyrocal.errors import excerpt
from gyrocal.io.yamlfile import TelemetryError, check_schema, read_yaml, schema
from gyrocal.model.channels import Channel, channel_sets
from gyrocal.model.sensorclass import SENSOR_CLASSES
from gyrocal.model.units import AXES

__all__ = [
    "CHANNEL_PATTERN",
    "DEFAULT_NOISE_GROUP",
    "DIRECTIONS",
    "GM_CLOCK_AUTO",
    "GM_CLOCK_KEY",
    "GYRO_KEYS",
    "NAME_MAX",
    "NAME_PATTERN",
    "NORM_REFUSE_TOL",
    "PERIODIC_TAIL",
    "RESERVED_NAMES",
    "SIGMA_IS",
    "SIGMA_IS_KEY",
    "Labelled",
    "Maneuver",
    "TelemetryError",
    "default_name",
    "fail",
    "read_meta",
    "stated_clock_s_per_rad",
    "turn_name",
]

NORM_REFUSE_TOL = 1e-3
"""Further than this from 1 a quaternion is refused: rounding to as few as three decimals stays
inside, a wrong column does not."""
NAME_PATTERN = re.compile(r"\A[A-Za-z0-9_]+\Z")
r"""A campaign name, maneuver id or channel name, matched whole (`re.fullmatch`; ``\Z``, unlike ``$``,
does not match before a final newline, so ``.match`` is whole too): ``evil\n`` is refused. The schema
states it for ``name``; it is stated here too because maneuver ids and channel names take it as well."""
CHANNEL_PATTERN = re.compile(r"\A(?:dtg(\d+)_(roll|pitch|yaw))\Z")
_NAME_SCHEMA = schema("campaign")["properties"]["name"]
_NAME_REFUSED = _NAME_SCHEMA["not"]["anyOf"]
NAME_MAX = int(_NAME_SCHEMA["maxLength"])
"""The longest campaign name (``campaign.schema.json``, which states it): it names folders and files of a
run (``results/<name>/``, ``logs/<name>/``), and a file system refuses a name over 255 bytes ("File name
too long")."""
PERIODIC_TAIL = re.compile(next(s["pattern"] for s in _NAME_REFUSED if "pattern" in s))
"""A name ending in one part repeated 20 times or more (``run_000000000000000000000000``; the schema's
pattern): Snakemake refuses such a wildcard value (PeriodicWildcardError), taking it for an endless
recursion of a rule."""
RESERVED_NAMES = tuple(next(s["enum"] for s in _NAME_REFUSED if "enum" in s))
"""Names no campaign may take (the schema's): the folders ``results/fleet`` (a fleet's summary),
``results/plan`` (``gyrocal plan``'s default) and ``results/study`` (the validation study's default)."""
DIRECTIONS = ("+", "-", "both")
"""A maneuver turns one way, the other, or both (several turns each way, no inertial holds)."""
DEFAULT_NOISE_GROUP = "all"
"""The noise group of a maneuver that names none: one group, one noise level, for the campaign."""

GYRO_KEYS = {"arw_deg_sqrt_h", "range_deg_s", "rate_hz", "sensor_class"}
"""What ``campaign.yaml``'s ``gyro:`` may hold: its noise, its range, its sampling rate and its sensor class
(`gyrocal.model.sensorclass`, whose default priors the fit takes)."""


class Labelled:
    """What a maneuver's labels say, for anything with ``axis`` and ``direction`` (`Maneuver`, and the
    preprocessed `gyrocal.maneuvers.preprocess.ManeuverData`)."""

    @property
    def free(self) -> bool:
        """Free motion: no single axis and direction are declared; the motion itself says what it turns."""
        return self.axis is None

    @property
    def turn(self) -> str:
        """The rotation as reports name it: ``+yaw``, ``-roll``, ``both yaw``, or ``free`` (free motion)."""
        return turn_name(self.axis, self.direction)


@dataclass(frozen=True)
class Maneuver(Labelled):
    id: str
    axis: str | None
    """The single axis it turns about; None for free motion (any rate profile, holds optional)."""
    direction: str | None
    """``+``, ``-`` or ``both``; None for free motion."""
    t_start: float
    t_end: float
    in_loop: tuple = ()
    noise_group: str = DEFAULT_NOISE_GROUP
    """The maneuvers sharing one noise level (a trial, a recording, a segment): a name."""

    @property
    def sign(self) -> float:
        """+1 or -1; 0 for a maneuver that turns both ways or moves freely."""
        return {"+": 1.0, "-": -1.0}.get(self.direction, 0.0)


def turn_name(axis, direction) -> str:
    """A maneuver's rotation as reports name it (`Maneuver.turn`): ``free`` without an axis."""
    if axis is None:
        return "free"
    return f"both {axis}" if direction == "both" else f"{direction}{axis}"


def fail(path, message, where: str = "", todo: str = ""):
    """Refuse the file ``path``: ``message`` says what is wrong (after ``where`` in it, if given)."""
    raise TelemetryError.at(path, message, where, todo)


def _parse_channels(path, raw) -> tuple:
    if not isinstance(raw, dict) or not raw:
        fail(path, "'channels' must map each gyro channel name to {axis: roll|pitch|yaw} (and, for a DTG, dtg: N)")
    channels = []
    for name, entry in raw.items():
        where = f"channels.{name}"
        if not NAME_PATTERN.fullmatch(str(name)):
            fail(path, f"{where}: a channel name may hold only letters, digits and '_'")
        if not isinstance(entry, dict) or "axis" not in entry or set(entry) - {"dtg", "axis"}:
            fail(path, f"{where}: needs the key 'axis' (roll, pitch or yaw) and may have 'dtg' (the DTG's number)")
        if entry["axis"] not in AXES:
            fail(path, f"{where}.axis: must be one of {list(AXES)}, got {excerpt(entry['axis'])}")
        dtg = entry.get("dtg")
        if dtg is not None and (not isinstance(dtg, int) or isinstance(dtg, bool)):
            fail(path, f"{where}.dtg: must be a whole number, got {excerpt(dtg)}")
        match = CHANNEL_PATTERN.fullmatch(str(name))
        if match and (int(match.group(1)), match.group(2)) != (dtg, entry["axis"]):
            fail(path, f"{where}: a name dtg<N>_<axis> needs dtg: N and that axis; got dtg/axis "
                        f"({dtg}, {entry['axis']})")
        channels.append(Channel(str(name), dtg, entry["axis"]))
    return tuple(channels)


def _parse_maneuvers(path, raw, channels) -> tuple:
    """The maneuvers, with their in-loop channels (any names: each channel's axis is its ``axis:``)."""
    axis_of = {c.name: c.axis for c in channels}
    channel_names = list(axis_of)
    if not isinstance(raw, list) or not raw:
        fail(path, "'maneuvers' must be a non-empty list")
    allowed = {"id", "axis", "direction", "t_start", "t_end", "in_loop", "noise_group"}
    seen = set()
    maneuvers = []
    for i, m in enumerate(raw):
        where = f"maneuvers[{i}]"
        if not isinstance(m, dict):
            fail(path, f"{where}: must be a mapping")
        missing = {"id", "t_start", "t_end"} - set(m)
        if missing:
            fail(path, f"{where}: missing key(s) {sorted(missing)}")
        if ("axis" in m) != ("direction" in m):
            fail(path, f"{where}: has {'axis' if 'axis' in m else 'direction'} without "
                       f"{'direction' if 'axis' in m else 'axis'}: a single-axis maneuver needs both, free motion neither")
        if set(m) - allowed:
            fail(path, f"{where}: unknown key(s) {sorted(set(m) - allowed)}")
        mid = str(m["id"])
        where = f"maneuvers[{i}] ({mid})"
        if not NAME_PATTERN.fullmatch(mid):
            fail(path, f"{where}.id: only letters, digits and '_' are allowed")
        if mid in seen:
            fail(path, f"{where}.id: duplicate maneuver id")
        seen.add(mid)
        labelled = "axis" in m
        if labelled and m["axis"] not in AXES:
            fail(path, f"{where}.axis: must be one of {list(AXES)}, got {excerpt(m['axis'])}")
        if labelled and str(m["direction"]) not in DIRECTIONS:
            fail(path, f"{where}.direction: must be \"+\", \"-\" or both, got {excerpt(m['direction'])}")
        for key in ("t_start", "t_end"):
            if not _is_number(m[key]):
                fail(path, f"{where}.{key}: must be a time in seconds, got {excerpt(m[key])}")
        t0, t1 = float(m["t_start"]), float(m["t_end"])
        if not t1 > t0:
            fail(path, f"{where}: t_end ({t1}) must be after t_start ({t0})")
        in_loop = tuple(m.get("in_loop") or ())
        for name in in_loop:
            if name not in channel_names:
                fail(path, f"{where}.in_loop: unknown channel {excerpt(name)} (channels: {channel_names})")
        if in_loop:
            axes = sorted(axis_of[name] for name in in_loop)
            if axes != sorted(AXES):
                fail(path, f"{where}.in_loop: needs one channel per axis roll, pitch, yaw; got {list(in_loop)} "
                           f"(axes {[axis_of[name] for name in in_loop]})")
        group = m.get("noise_group", DEFAULT_NOISE_GROUP)
        if not isinstance(group, str) or not NAME_PATTERN.fullmatch(group):
            fail(path, f"{where}.noise_group: a group's name holds only letters, digits and '_', got {excerpt(group)}",
                 todo="name the maneuvers that share a noise level alike, e.g. noise_group: trial_1")
        maneuvers.append(Maneuver(mid, m["axis"] if labelled else None, str(m["direction"]) if labelled else None,
                                  t0, t1, in_loop, group))
    ordered = sorted(maneuvers, key=lambda m: m.t_start)
    for first, second in itertools.pairwise(ordered):
        if second.t_start < first.t_end:
            fail(path, f"maneuvers {first.id} [{first.t_start}, {first.t_end}] s and {second.id} "
                        f"[{second.t_start}, {second.t_end}] s overlap: their samples would count twice")
    return tuple(maneuvers)


def read_meta(directory) -> dict:
    """Parse and check ``campaign.yaml`` alone (name, channels, maneuvers, noise knowledge)."""
    directory = Path(directory)
    if not directory.is_dir():
        raise TelemetryError(f"{directory}: campaign directory not found")
    cpath = directory / "campaign.yaml"
    document = read_yaml(cpath)
    check_schema(document, "campaign", label_ids=True)
    meta = document.data
    if not isinstance(meta, dict):
        fail(cpath, "must be a mapping with 'channels' and 'maneuvers'")
    unknown = set(meta) - {"name", "channels", "star_tracker", "gyro", "maneuvers"}
    if unknown:
        fail(cpath, f"unknown key(s) {sorted(unknown)}")
    for key in ("channels", "maneuvers"):
        if key not in meta:
            fail(cpath, f"missing key '{key}'")
    channels = _parse_channels(cpath, meta["channels"])
    try:
        channel_sets(channels)
    except ValueError as exc:
        fail(cpath, f"channels: {exc}")
    for key in ("star_tracker", "gyro"):
        if meta.get(key) is not None and not isinstance(meta[key], dict):
            fail(cpath, f"{key}: must be a mapping of its noise knowledge (e.g. {key}: "
                         f"{{{'arw_deg_sqrt_h' if key == 'gyro' else 'sigma_cross_arcsec'}: ...}}), got {excerpt(meta[key])}")
    gyro = meta.get("gyro") or {}
    if set(gyro) - GYRO_KEYS:
        fail(cpath, f"gyro: unknown key(s) {sorted(set(gyro) - GYRO_KEYS)}")
    if "sensor_class" in gyro and gyro["sensor_class"] not in SENSOR_CLASSES:
        fail(cpath, f"gyro.sensor_class: one of {sorted(SENSOR_CLASSES)}, got {excerpt(gyro['sensor_class'])}")
    for key in ("arw_deg_sqrt_h", "range_deg_s", "rate_hz"):
        if key in gyro and not _positive_number(gyro[key]):
            fail(cpath, f"gyro.{key}: must be a positive number")
    name = str(meta.get("name") or default_name(directory))
    where = f"name (line {document.line(['name'])})" if meta.get("name") else "name (from the directory's)"
    if not NAME_PATTERN.fullmatch(name):
        fail(cpath, f"only letters, digits and '_' are allowed, got {excerpt(name)}", where)
    if len(name) > NAME_MAX:
        fail(cpath, f"{len(name)} characters, over the {NAME_MAX} a campaign name may have (it names the run's "
                    f"folders): {name[:20]}...", where, "give the campaign a shorter name: name: ...")
    if repeated := PERIODIC_TAIL.search(name):
        fail(cpath, f"{excerpt(name)} ends in {repeated.group(1)!r} repeated {len(repeated.group(0)) // len(repeated.group(1))} "
                    "times, which Snakemake refuses in a run's paths (it takes it for an endless recursion)", where,
             "give the campaign a name without such a repetition: name: ...")
    if name in RESERVED_NAMES:
        fail(cpath, f"{excerpt(name)} is reserved: results/{name} is where gyrocal writes "
                    + {"fleet": "a fleet's summary", "plan": "gyrocal plan's tables",
                       "study": "the validation study"}[name], where, "give the campaign another name: name: ...")
    return {"name": name, "channels": channels,
            "maneuvers": _parse_maneuvers(cpath, meta["maneuvers"], channels),
            "star_tracker": _parse_star_tracker(cpath, meta.get("star_tracker") or {}, document.line),
            "gyro": dict(gyro)}


def default_name(directory) -> str:
    """A campaign's name when ``campaign.yaml`` has none: its directory's, with every character
    other than letters, digits and ``_`` made ``_`` (results go to ``results/<name>/``)."""
    return re.sub(r"[^A-Za-z0-9_]", "_", Path(directory).resolve().name)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)


def _positive_number(value) -> bool:
    return _is_number(value) and value > 0


GM_CLOCK_KEY = "gm_clock_s_per_rad"
"""``star_tracker``'s key: the seconds the clock of the reference error's Gauss-Markov part runs per radian
the body turns, beside time (`gyrocal.inference.errormodel.gm_clock_steps`); absent, 0."""

GM_CLOCK_AUTO = "auto"
"""Its value that asks for the clock to be chosen from the data (`gyrocal.inference.clock`)."""

SIGMA_IS_KEY = "sigma_is"
"""``star_tracker``'s key: what ``sigma_cross_arcsec`` and ``sigma_about_arcsec`` state, one of
`SIGMA_IS`: the reference's ``total`` sd (a data sheet's, the default), or its ``white`` part alone (what a
recording at rest shows, as `gyrocal import` measures it: `gyrocal.io.rests.reference_noise_at_rest`)."""

SIGMA_IS = ("total", "white")


def stated_clock_s_per_rad(star_tracker: dict) -> float | None:
    """The clock ``star_tracker`` states (s a radian turned; 0 where it states none), or None where it asks
    for `GM_CLOCK_AUTO`."""
    value = star_tracker.get(GM_CLOCK_KEY, 0.0)
    return None if value == GM_CLOCK_AUTO else float(value)


def _parse_star_tracker(path, raw, line_of=lambda keys: "?") -> dict:
    allowed = {"sigma_cross_arcsec", "sigma_about_arcsec", "boresight_body", "mounting", "rate_hz", "st_jitter_ms",
               GM_CLOCK_KEY, SIGMA_IS_KEY}
    if set(raw) - allowed:
        fail(path, f"star_tracker: unknown key(s) {sorted(set(raw) - allowed)}")
    if SIGMA_IS_KEY in raw and raw[SIGMA_IS_KEY] not in SIGMA_IS:
        fail(path, f"star_tracker.{SIGMA_IS_KEY}: one of {', '.join(SIGMA_IS)}; got {excerpt(raw[SIGMA_IS_KEY])}")
    if SIGMA_IS_KEY in raw and not {"sigma_cross_arcsec", "sigma_about_arcsec"} <= set(raw):
        fail(path, f"star_tracker.{SIGMA_IS_KEY}: says what sigma_cross_arcsec and sigma_about_arcsec state, so it "
                   "needs both beside it (the config's defaults are a star tracker's total)")
    for key in ("sigma_cross_arcsec", "sigma_about_arcsec", "rate_hz", "st_jitter_ms"):
        if key in raw and not _positive_number(raw[key]):
            fail(path, f"star_tracker.{key}: must be a positive number")
    out = dict(raw)
    if "boresight_body" in raw:
        b = raw["boresight_body"]
        if not isinstance(b, list) or len(b) != 3 or not all(_is_number(v) for v in b) or not any(b):
            fail(path, f"star_tracker.boresight_body: must be a non-zero 3-vector of numbers in body axes, "
                        f"e.g. [0, 0, 1]; got {excerpt(b)}")
        b = np.asarray(b, dtype=float)
        norm = float(np.linalg.norm(b))
        if abs(norm - 1.0) > NORM_REFUSE_TOL:
            fail(path, f"must be a unit vector in body axes; {b.tolist()} has norm {norm:.6g}, off 1 by more than "
                       f"{NORM_REFUSE_TOL:g} (a wrong entry, or a vector not yet normalised?)",
                 f"star_tracker.boresight_body (line {line_of(['star_tracker', 'boresight_body'])})",
                 "write the boresight's unit vector, e.g. [0, 0, 1]")
        out["boresight_body"] = (b if abs(norm - 1.0) <= 1e-12 else b / norm).tolist()  # inside: rounding
    if "mounting" in raw:
        q = raw["mounting"]
        if q != "estimate" and (not isinstance(q, list) or len(q) != 4 or not all(_is_number(v) for v in q)
                                or abs(np.linalg.norm(q) - 1.0) > NORM_REFUSE_TOL):
            fail(path, "star_tracker.mounting: the reference frame's attitude in body axes, a unit quaternion "
                        f"[q1, q2, q3, q4] (scalar last), or estimate; got {excerpt(q)}")
    return out
