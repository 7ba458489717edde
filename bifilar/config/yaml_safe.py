"""Reading config YAML safely: plain data only, every problem with its place.

A ``SafeLoader`` subclass (no Python object construction: ``!!python/...``
tags are an error), duplicate keys rejected (plain PyYAML silently keeps the
last one), files limited to :data:`MAX_CONFIG_BYTES`, alias expansion
("billion laughs") limited to :data:`MAX_YAML_VALUES` values, recursive
aliases and absurd nesting rejected.  Exponent floats without a dot or an
exponent sign (``1e-3``, ``2E5``), which YAML 1.1 reads as text, are read
as numbers (YAML 1.2).  Part of :mod:`bifilar.config`.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Any

import yaml

from ..errors import ConfigErrors, InputError
from .fields import _YAML11_SURPRISE, _clip, _join, _one_line

MAX_CONFIG_BYTES = 1_000_000
"""Largest config file read, bytes (a real config is ~1-10 kB)."""
MAX_YAML_VALUES = 100_000
"""Most values (scalars, lists, mappings) a config may hold once YAML
aliases are expanded; guards every consumer against alias bombs."""

_FLOAT_12 = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
_SAFE_TAGS = set(yaml.SafeLoader.yaml_constructors) | {
    "tag:yaml.org,2002:merge", "tag:yaml.org,2002:value",
}


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that also reads YAML 1.2 exponent floats (``1e-3``).

    Duplicate keys, unsafe tags and alias bombs are found on the composed
    node graph (:func:`_scan_nodes`) before anything is constructed, so that
    each problem can be reported with its dotted path."""


_UniqueKeyLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789."))


def read_yaml(path: str | os.PathLike) -> Any:
    """Read a YAML file safely: a regular UTF-8 file of at most
    :data:`MAX_CONFIG_BYTES` bytes, parsed by :func:`parse_yaml`.

    Raises :class:`~bifilar.errors.InputError` (field ``config``) for a file
    that cannot be read and :class:`~bifilar.errors.ConfigErrors` for YAML
    problems."""
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise InputError("config", f"file not found: {p}") from None
    except OSError as exc:
        raise InputError("config", f"cannot read {p}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError("config", f"is a directory, not a config file: {p}")
    if not stat.S_ISREG(st.st_mode):
        raise InputError("config", f"not a regular file: {p}")
    if st.st_size > MAX_CONFIG_BYTES:
        raise InputError("config", f"file is {st.st_size} bytes; configs are limited to {MAX_CONFIG_BYTES} bytes")
    try:
        with open(p, "rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        raise InputError("config", f"cannot read {p}: {exc.strerror or exc}") from None
    if len(data) > MAX_CONFIG_BYTES:  # grew while we looked
        raise InputError("config", f"file is over {MAX_CONFIG_BYTES} bytes; configs are limited to {MAX_CONFIG_BYTES} bytes")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputError("config", f"not UTF-8 text (line {line}: {exc.reason} 0x{data[exc.start]:02x}); "
                                   "save the file as UTF-8") from None
    return parse_yaml(text)


def parse_yaml(text: str) -> Any:
    """Parse YAML text into plain data (dict, list, str, int, float, bool, None).

    Raises
    ------
    ConfigErrors
        Every duplicate key, unsupported tag (``!!python/object`` ...),
        non-scalar key, recursive alias or oversized alias expansion, each
        with its dotted path; or one syntax error with its line and column.
    """
    if len(text) > MAX_CONFIG_BYTES:
        raise InputError("config", f"text is {len(text)} characters; configs are limited to {MAX_CONFIG_BYTES}")
    try:
        loader = _UniqueKeyLoader(text)
    except yaml.reader.ReaderError as exc:  # the reader rejects control characters up front
        line = text.count("\n", 0, exc.position) + 1
        col = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise InputError(f"line {line}, column {col}",
                         f"YAML syntax error: control character #x{exc.character:04x} is not allowed") from None
    try:
        try:
            node = loader.get_single_node()
        except yaml.YAMLError as exc:
            raise _yaml_error(exc) from None
        except RecursionError:
            raise InputError("config", "nested too deeply (lists or mappings inside each other hundreds of levels deep)") from None
        if node is None:
            return None
        problems = _scan_nodes(node)
        if problems:
            raise ConfigErrors(problems)
        try:
            return _unshare(loader.construct_document(node))
        except yaml.YAMLError as exc:
            raise _yaml_error(exc) from None
        except RecursionError:
            raise InputError("config", "nested too deeply") from None
        except Exception as exc:  # noqa: BLE001 - PyYAML's scalar constructors fail on e.g. "!!int abc", "!!int "
            raise InputError("config", f"cannot read a value ({type(exc).__name__}: {_clip(str(exc), 80)}); "
                                       "check explicit tags such as !!int") from None
    finally:
        loader.dispose()


def _unshare(data: Any) -> Any:
    """A copy of constructed YAML data in which no list or mapping appears
    twice.  PyYAML builds one object per anchor and hands it to every alias
    (``*p0``), so without this an edit of one place (a sweep of
    ``rig.attachments.0.1``) would silently edit every place that named the
    same anchor.  :func:`copy.deepcopy` keeps such sharing (its memo), hence
    the explicit rebuild; the size is bounded by :data:`MAX_YAML_VALUES` and
    recursive aliases were rejected before."""
    if isinstance(data, dict):
        return {k: _unshare(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_unshare(v) for v in data]
    return data


def _short_tag(tag: str) -> str:
    return "!!" + tag[len("tag:yaml.org,2002:"):] if tag.startswith("tag:yaml.org,2002:") else tag


def _yaml_error(exc: yaml.YAMLError) -> InputError:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "config"
    problem = getattr(exc, "problem", None) or str(exc)
    context = getattr(exc, "context", None)
    msg = f"YAML syntax error: {problem}" + (f" ({context})" if context and context not in problem else "")
    return InputError(where, _one_line(msg))


_STR = "tag:yaml.org,2002:str"


#: keys whose values are times, where a stopwatch's ``m:ss.ss`` is meant as base 60 (``0:19.07`` is 19.07 s)
_TIME_KEYS = {"times", "period"}


def _as_text_if_yaml11_number(node: yaml.ScalarNode, path: str) -> None:
    """Retag a plain scalar that YAML 1.1 reads as a base-60 or octal number
    (``_YAML11_SURPRISE``) as a string, in place; base 60 stays a number
    under a time key (:data:`_TIME_KEYS`, the last name in the dotted
    ``path``)."""
    if node.style or node.tag not in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float") \
            or not _YAML11_SURPRISE.match(node.value):
        return
    names = [p for p in str(path).split(".") if p and not p.isdigit()]
    if ":" in node.value and names and names[-1] in _TIME_KEYS:
        return
    node.tag = _STR


def _scan_nodes(root: yaml.Node) -> list[InputError]:
    """Walk the composed node graph (aliases followed, iteratively) and
    collect: duplicate keys, non-scalar keys, unsafe tags, recursive aliases,
    more than :data:`MAX_YAML_VALUES` values."""
    errors: list[tuple[int, InputError]] = []  # (line, error): reported in file order
    count = 0
    on_path: set[int] = set()
    stack: list[tuple[bool, yaml.Node, str]] = [(True, root, "")]
    while stack:
        enter, node, path = stack.pop()
        if not enter:
            on_path.discard(id(node))
            continue
        line = node.start_mark.line + 1
        if id(node) in on_path:
            errors.append((line, InputError(path or "config", f"recursive YAML alias: the value at line {line} contains itself")))
            continue
        count += 1
        if count > MAX_YAML_VALUES:
            return [InputError("config", f"more than {MAX_YAML_VALUES} values once YAML aliases (*name) are expanded; "
                                         "configs are limited to that")]
        if node.tag not in _SAFE_TAGS:
            errors.append((line, InputError(
                path or "config",
                f"unsupported YAML tag {_clip(_short_tag(node.tag))} (line {line}); only plain data is read: mappings, lists, "
                "numbers, strings, true/false, null")))
            continue
        if isinstance(node, yaml.ScalarNode):
            _as_text_if_yaml11_number(node, path)
            continue
        on_path.add(id(node))
        stack.append((False, node, path))
        if isinstance(node, yaml.SequenceNode):
            for i, child in reversed(list(enumerate(node.value))):
                stack.append((True, child, _join(path, i)))
        elif isinstance(node, yaml.MappingNode):
            seen: dict[tuple[str, str], int] = {}
            children = []
            for key_node, value_node in node.value:
                kline = key_node.start_mark.line + 1
                if key_node.tag == "tag:yaml.org,2002:merge":
                    children.append((value_node, path))
                    continue
                if not isinstance(key_node, yaml.ScalarNode):
                    errors.append((kline, InputError(
                        path or "config",
                        f"a key at line {kline} is a {'list' if isinstance(key_node, yaml.SequenceNode) else 'mapping'}; "
                        "keys must be plain names")))
                    continue
                k = (key_node.tag, key_node.value)
                child_path = _join(path, key_node.value)
                if k in seen:
                    errors.append((kline, InputError(
                        child_path,
                        f"duplicate key '{_clip(key_node.value)}' (lines {seen[k]} and {kline}); "
                        "YAML would silently keep only the last")))
                else:
                    seen[k] = kline
                children.append((value_node, child_path))
            for child, cpath in reversed(children):
                stack.append((True, child, cpath))
    return [e for _, e in sorted(errors, key=lambda le: le[0])]
