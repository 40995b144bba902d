"""Reading the YAML files users write (configs, user objects, grippers, cups, bins).

:func:`read_yaml` is the one entry point: it names the file in every error (missing, a folder,
binary or not UTF-8, not YAML) and reads numbers the way people write them. PyYAML follows
YAML 1.1, where ``1.0e6`` and ``1e-3`` (an exponent without a sign, or a mantissa without a
dot) are *strings*; here they are floats, as in YAML 1.2 and JSON. A key written twice in one
mapping is an error naming the key and both lines (PyYAML would keep the last value silently);
keys brought in by a ``<<`` merge may still be overridden.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import yaml

from mgn.errors import InvalidArgumentError, IoError

__all__ = ["YamlLoader", "parse_yaml", "read_yaml"]


class YamlLoader(yaml.SafeLoader):  # type: ignore[misc]  # PyYAML has no type information
    """``yaml.SafeLoader`` that also reads ``1e6``, ``1.0e6`` and ``-2.5E-3`` as floats and
    refuses a key written twice in one mapping."""

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, yaml.Node] = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue  # `<<: *anchor` brings keys that the mapping may override
                key = self.construct_object(key_node, deep=True)
                try:
                    earlier = first.get(key)
                except TypeError:  # an unhashable key: the base class reports it
                    continue
                if earlier is not None:
                    raise yaml.constructor.ConstructorError(
                        "while reading a mapping",
                        node.start_mark,
                        f"found the key {key!r} twice (first on line {earlier.start_mark.line + 1}"
                        f", again on line {key_node.start_mark.line + 1}); keep one",
                        key_node.start_mark,
                    )
                first[key] = key_node
        mapping: dict[Any, Any] = super().construct_mapping(node, deep=deep)
        return mapping


# YAML 1.2 core-schema floats (plus the YAML 1.1 forms PyYAML already knows).
_FLOAT = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.VERBOSE,
)
YamlLoader.yaml_implicit_resolvers = {
    k: [(tag, rx) for tag, rx in v if tag != "tag:yaml.org,2002:float"]
    for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
YamlLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))


def parse_yaml(text: str, source: str = "<string>") -> Any:
    """The data of YAML ``text``; InvalidArgumentError naming ``source`` when it is not YAML."""
    try:
        return yaml.load(text, Loader=YamlLoader)  # a SafeLoader subclass
    except yaml.YAMLError as e:
        raise InvalidArgumentError(f"'{source}' is not valid YAML: {e}") from e


def read_yaml(path: str | os.PathLike[str], what: str = "YAML file") -> Any:
    """The data of the YAML file ``path``.

    Args:
        path: the file.
        what: what the file is, for the messages (e.g. ``"config file"``).

    Raises:
        IoError: the file does not exist, is a folder or cannot be read.
        InvalidArgumentError: the file is binary, not UTF-8 text or not valid YAML.
    """
    p = Path(path)
    if p.is_dir():
        raise IoError(f"{what} '{p}' is a folder; expected a YAML file")
    try:
        raw = p.read_bytes()
    except FileNotFoundError as e:
        raise IoError(f"{what} not found: '{p}'") from e
    except OSError as e:
        raise IoError(f"{what} '{p}' cannot be read: {e.strerror or e}") from e
    if b"\x00" in raw:
        raise InvalidArgumentError(f"{what} '{p}' is a binary file; expected YAML text")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise InvalidArgumentError(
            f"{what} '{p}' is not UTF-8 text (byte {e.start}); expected a YAML file"
        ) from e
    try:
        return yaml.load(text, Loader=YamlLoader)
    except yaml.YAMLError as e:
        raise InvalidArgumentError(f"{what} '{p}' is not valid YAML: {e}") from e
