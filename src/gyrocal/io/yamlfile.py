"""The one reader of every YAML file gyrocal reads (``campaign.yaml``, scenarios, importer mappings,
configs), and their JSON Schemas (``gyrocal/io/schemas/``).

A YAML file is input like any other, so it is refused before it can cost anything: a file over
`MAX_BYTES`, a path that is a directory or missing, text that is not UTF-8, an anchor or an alias
(refused at the first one, while the parser streams its events, before any node is built: a
"billion laughs" expansion never starts), nesting deeper than `MAX_DEPTH`, a key given twice in
one mapping (the last would win silently), a merge key, several documents, and invalid YAML.
Each refusal is a `TelemetryError` naming the file and the line. `check_schema` then validates
the data against one of the package's schemas (draft 2020-12) and turns the first violation into
a `TelemetryError` naming the key path (``maneuvers[2].direction``), the line and, in words,
what the schema wants there.
"""

import functools
import json
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import yaml
from yaml import nodes

from gyrocal.errors import InputError

__all__ = ["MAX_BYTES", "MAX_DEPTH", "SCHEMAS", "SafeYamlLoader", "TelemetryError", "YamlDocument", "check_schema",
           "load_yaml", "read_yaml", "schema"]

MAX_BYTES = 1 << 20
"""A YAML file larger than this (1 MiB) is refused unread: a campaign.yaml is a few KB."""
MAX_DEPTH = 32
"""Mappings and lists nested deeper than this are refused (gyrocal's files nest three or four deep)."""
SCHEMAS = {"campaign": "campaign.schema.json", "scenario": "scenario.schema.json", "mapping": "mapping.schema.json",
           "verdict": "verdict.schema.json", "diagnostics": "diagnostics.schema.json", "sampler": "sampler.schema.json",
           "refusal": "refusal.schema.json"}
"""The JSON Schema of each kind of file, in ``gyrocal/io/schemas/``: the inputs gyrocal reads, and the
outputs scripts read (`gyrocal.io.outputs.output_errors`); one may refer to another by its file name."""
_MERGE_TAG = "tag:yaml.org,2002:merge"


class TelemetryError(InputError):
    """Bad campaign input; the message names the file, the row, line or key, and the fault."""


class SafeYamlLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """PyYAML's safe loader (libyaml's, where PyYAML was built with it): plain data only, no
    Python objects. `read_yaml` streams its events once to refuse anchors, aliases and deep
    nesting before it composes any node."""


@dataclass(frozen=True)
class YamlDocument:
    """A YAML file as read: its data, and its node tree to find the line of any key path."""

    path: Path
    data: object
    root: object = None

    def node(self, keys):
        """The node at the key path ``keys`` (str keys and int indices), or the deepest one found."""
        node = self.root
        for key in keys:
            if isinstance(node, nodes.MappingNode):
                found = [v for k, v in node.value if isinstance(k, nodes.ScalarNode) and k.value == str(key)]
                if not found:
                    break
                node = found[0]
            elif isinstance(node, nodes.SequenceNode) and isinstance(key, int) and 0 <= key < len(node.value):
                node = node.value[key]
            else:
                break
        return node

    def line(self, keys=(), key_itself: bool = False) -> int:
        """The line (from 1) of the value at ``keys``; with ``key_itself``, of its last key."""
        keys = list(keys)
        if key_itself and keys and isinstance(self.node(keys[:-1]), nodes.MappingNode):
            for k, _ in self.node(keys[:-1]).value:
                if isinstance(k, nodes.ScalarNode) and k.value == str(keys[-1]):
                    return k.start_mark.line + 1
        node = self.node(keys)
        return 1 if node is None else node.start_mark.line + 1


def _refuse(path, what, line=None, todo=""):
    raise TelemetryError.at(path, what, f"line {line}" if line else "", todo)


def _text(path: Path) -> str:
    if not path.exists():
        _refuse(path, "file not found")
    if not path.is_file():
        _refuse(path, "is not a file (a directory?)", todo="give the YAML file itself")
    with path.open("rb") as handle:
        raw = handle.read(MAX_BYTES + 1)
    if len(raw) > MAX_BYTES:
        _refuse(path, f"is larger than {MAX_BYTES} bytes ({MAX_BYTES // 1024} KiB), far more than any gyrocal "
                      "YAML file holds", todo="check that this is the file meant")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        _refuse(path, f"is not UTF-8 text (byte {exc.start}: {raw[exc.start:exc.start + 1]!r})",
                raw[:exc.start].count(b"\n") + 1)


def _scan(path, text):
    """Stream the parser's events: refuse the first anchor or alias, and nesting past `MAX_DEPTH`."""
    loader = SafeYamlLoader(text)
    try:
        depth = 0
        while loader.check_event():
            event = loader.get_event()
            line = event.start_mark.line + 1
            if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
                kind = "an alias (*" if isinstance(event, yaml.AliasEvent) else "an anchor (&"
                _refuse(path, f"{kind}{event.anchor}): gyrocal reads no YAML anchors or aliases", line,
                        "write each value out in full")
            if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                depth += 1
                if depth > MAX_DEPTH:
                    _refuse(path, f"nests mappings or lists more than {MAX_DEPTH} deep", line)
            elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                depth -= 1
    finally:
        loader.dispose()


def _check_keys(path, root):
    """Refuse a key given twice in one mapping (at any depth), and merge keys."""
    stack = [root] if root is not None else []
    while stack:
        node = stack.pop()
        if isinstance(node, nodes.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, nodes.MappingNode):
            seen = {}
            for key, value in node.value:
                line = key.start_mark.line + 1
                if key.tag == _MERGE_TAG:
                    _refuse(path, "a merge key (<<): gyrocal reads none", line, "write the keys out in full")
                if isinstance(key, nodes.ScalarNode):
                    if (key.tag, key.value) in seen:
                        _refuse(path, f"the key {key.value!r} is given twice in one mapping, on line "
                                      f"{seen[key.tag, key.value]} and on line {line} (YAML keeps only the last)",
                                line, "keep one of them")
                    seen[key.tag, key.value] = line
                stack.extend((key, value))


def read_yaml(path) -> YamlDocument:
    """Read one YAML file through the safe loader, refusing what the module's docstring lists."""
    path = Path(path)
    text = _text(path)
    try:
        _scan(path, text)
        loader = SafeYamlLoader(text)
        try:
            root = loader.get_single_node()
            _check_keys(path, root)
            data = None if root is None else loader.construct_document(root)
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        context = getattr(exc, "context", None)
        hint = ""
        if "sequence entries are not allowed" in str(exc):
            hint = 'a bare - starts a YAML list: quote a direction, direction: "-"'
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise TelemetryError.at(path, "not valid YAML: " + (f"{context}, " if context else "") + problem, where,
                                hint) from None
    return YamlDocument(path, data, root)


def load_yaml(path):
    """The data of one YAML file, read by `read_yaml`."""
    return read_yaml(path).data


@functools.cache
def schema(kind: str) -> dict:
    """The JSON Schema of a kind of file (a key of `SCHEMAS`)."""
    return json.loads((resources.files("gyrocal.io") / "schemas" / SCHEMAS[kind]).read_text())


@functools.cache
def _validator(kind: str):
    import jsonschema  # 0.07 s; only where a file is checked
    from referencing import Registry, Resource

    registry = Registry().with_resources((name, Resource.from_contents(schema(k))) for k, name in SCHEMAS.items())
    return jsonschema.Draft202012Validator(schema(kind), registry=registry)


def _deref(root: dict, sub):
    while isinstance(sub, dict) and "$ref" in sub:
        sub = root["$defs"][sub["$ref"].rsplit("/", 1)[1]]
    return sub


def _subschema(root: dict, sub, key):
    """The part of the schema ``sub`` that the instance's ``key`` (a key or an index) is checked against."""
    sub = _deref(root, sub)
    if not isinstance(sub, dict):
        return None
    if isinstance(key, int):
        return sub.get("items") if isinstance(sub.get("items"), dict) else None
    if key in sub.get("properties", {}):
        return sub["properties"][key]
    for pattern, part in sub.get("patternProperties", {}).items():
        if re.search(pattern, key):
            return part
    return sub.get("additionalProperties") if isinstance(sub.get("additionalProperties"), dict) else None


def _description(root: dict, sub):
    """A schema part's description (beside its ``$ref`` or in what it refers to), or None."""
    if isinstance(sub, dict) and "description" in sub:
        return sub["description"]
    sub = _deref(root, sub)
    return sub.get("description") if isinstance(sub, dict) else None


def _keypath(data, keys, label_ids: bool) -> str:
    out, value = "", data
    for key in keys:
        value = value[key]
        if isinstance(key, int):
            out += f"[{key}]"
            if label_ids and isinstance(value, dict) and isinstance(value.get("id"), (str, int)):
                ident = str(value["id"])
                out += f" ({ident})" if re.fullmatch(r"[A-Za-z0-9_]+", ident) else f" ({ident!r})"
        else:
            out += f".{key}" if out else str(key)
    return out


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 70 else text[:67] + "..."


_TYPES = {"object": "a mapping", "array": "a list", "string": "text", "number": "a number", "integer": "a whole number",
          "boolean": "true or false", "null": "empty"}


def _wanted(error) -> str:
    """What the failing keyword wants, in words, where no description says it."""
    kind, want = error.validator, error.validator_value
    if kind == "type":
        return "must be " + " or ".join(_TYPES[t] for t in ([want] if isinstance(want, str) else want))
    words = {"enum": lambda: f"must be one of {want}", "const": lambda: f"must be {want!r}",
             "minimum": lambda: f"must be >= {want}", "exclusiveMinimum": lambda: f"must be > {want}",
             "maximum": lambda: f"must be <= {want}", "exclusiveMaximum": lambda: f"must be < {want}",
             "minItems": lambda: f"must have at least {want} entries", "maxItems": lambda: f"must have at most {want} entries",
             "pattern": lambda: f"must match the pattern {want}", "minLength": lambda: "must not be empty",
             "uniqueItems": lambda: "must not repeat an entry"}
    return words[kind]() if kind in words else f"is not valid ({error.message})"


def check_schema(document: YamlDocument, kind: str, *, label_ids: bool = False):
    """Validate a read file against its schema; refuse the first violation in the file (the one on
    the lowest line) naming its key path and line. ``label_ids``: a list entry with an ``id`` is
    named by it too (``maneuvers[1] (yaw_neg)``)."""
    from jsonschema.exceptions import best_match

    errors = list(_validator(kind).iter_errors(document.data))
    if not errors:
        return
    root = schema(kind)
    first = min(document.line(e.absolute_path) for e in errors)
    error = best_match(e for e in errors if document.line(e.absolute_path) == first)
    keys = list(error.absolute_path)
    parts = [root]
    for key in keys:
        parts.append(_subschema(root, parts[-1], key))
    line = document.line(keys)
    todo = ""
    if error.validator == "required":
        what = f"missing key(s) {[k for k in error.validator_value if k not in error.instance]}"
    elif error.validator in ("additionalProperties", "unevaluatedProperties"):
        sub = _deref(root, error.schema)
        allowed = sub.get("properties", {})
        unknown = [k for k in error.instance if k not in allowed
                   and not any(re.search(p, str(k)) for p in sub.get("patternProperties", {}))]
        what = f"unknown key(s) {unknown}"
        todo = f"allowed: {sorted(allowed)}" if allowed else ""
        line = document.line([*keys, unknown[0]], key_itself=True) if unknown else line
    elif "propertyNames" in error.relative_schema_path:
        described = error.schema.get("description")
        keys.append(error.instance)
        line = document.line(keys, key_itself=True)
        what = f"must be {described}" if described else _wanted(error)
        what += f", got {_short(error.instance)}"
    else:
        candidates = [(len(keys), parts[-1])]
        if keys and isinstance(keys[-1], int):
            candidates.append((len(keys) - 1, parts[-2]))
        described = next(((n, _description(root, p)) for n, p in candidates if _description(root, p)), None)
        if described is not None:
            keys = keys[:described[0]]
            value = document.data
            for key in keys:
                value = value[key]
            what = f"must be {described[1]}, got {_short(value)}"
        else:
            what = f"{_wanted(error)}, got {_short(error.instance)}"
    where = _keypath(document.data, keys, label_ids)
    raise TelemetryError.at(document.path, f"{what} (line {line})", where, todo)
