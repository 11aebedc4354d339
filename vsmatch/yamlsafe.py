"""YAML as configs and calibrations are read: safe, and a key given twice is an error
(PyYAML keeps the last one silently, so ``arms:`` twice would drop the first)."""

from __future__ import annotations

import yaml


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """A mapping names one key twice; the message names the key and its line."""


class UniqueKeyLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a mapping with a key given twice."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    duplicate = key in seen
                except TypeError:  # an unhashable key: SafeLoader's own error follows
                    break
                if duplicate:
                    raise DuplicateKeyError(
                        None, None, f"the key '{str(key)[:40]}' is given twice (line "
                        f"{key_node.start_mark.line + 1})", key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


def load(text: str):
    """The YAML document in ``text`` (safe types only, every key once)."""
    return yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
