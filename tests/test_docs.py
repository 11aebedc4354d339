"""Docs that cannot go stale: every ``vsmatch`` command line in a fenced shell block of the
README and docs/ names a real command and real options (read from Click, nothing run), every
Python block imports and names what exists, each command's help ends with examples that
pass the same check, and no user-facing page names an issue number."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
import shlex
from pathlib import Path

import click
import click.testing
import pytest

import vsmatch
from vsmatch.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]
SHELL = {"sh", "bash", "shell", "console"}
FENCE = re.compile(r"^```(\w*)\s*\n(.*?)^```", re.S | re.M)
#: Options every command takes after its name (cli/common.verbosity_options) or before it.
GROUP_OPTIONS = {"-v", "--verbose", "-q", "--quiet", "--debug", "-h", "--help", "--version"}


def fenced_blocks(page: Path, languages: set[str]):
    """(line number, text) of each fenced block in one of ``languages``."""
    text = page.read_text(encoding="utf-8")
    for found in FENCE.finditer(text):
        if found.group(1) in languages:
            yield text[:found.start()].count("\n") + 1, found.group(2)


def command_lines(block: str):
    """The argument lists of the ``vsmatch`` (or ``python -m vsmatch``) commands in a shell
    block: continuations joined, comments dropped, each part of ``&&``, ``|``, ``;``."""
    for line in block.replace("\\\n", " ").splitlines():
        line = line.strip().removeprefix("$ ")
        words = shlex.split(line, comments=True)
        part: list[str] = []
        for word in [*words, ";"]:
            if word in {"&&", "||", "|", ";"}:
                while part and re.fullmatch(r"[A-Z_][A-Z0-9_]*=.*", part[0]):
                    part.pop(0)  # VAR=value before the command
                if part[:3] == ["python", "-m", "vsmatch"]:
                    part = ["vsmatch", *part[3:]]
                if part[:1] == ["vsmatch"]:
                    yield part[1:]
                part = []
            else:
                part.append(word)


def check_command_line(args: list[str]) -> None:
    """Raise AssertionError unless ``args`` names a real command and only its options."""
    command: click.Command = main
    position = 0
    while isinstance(command, click.Group):
        while position < len(args) and args[position] in GROUP_OPTIONS:
            position += 1
        if position == len(args):
            return  # `vsmatch --version`, `vsmatch datasets`
        name = args[position]
        assert name in command.commands, f"no command {name!r} in {' '.join(args)!r}"
        command = command.commands[name]
        position += 1
    options = {}
    for param in command.params:
        if isinstance(param, click.Option):
            for opt in [*param.opts, *param.secondary_opts]:
                options[opt] = param
    arguments = [p for p in command.params if isinstance(p, click.Argument)]
    positional = 0
    rest = args[position:]
    i = 0
    while i < len(rest):
        word = rest[i]
        if word.startswith("-") and not re.fullmatch(r"-\d.*", word):
            name, _, value = word.partition("=")
            if name in GROUP_OPTIONS:
                i += 1
                continue
            assert name in options, (f"{command.name}: no option {name!r} in "
                                     f"{' '.join(args)!r}")
            takes_value = not (options[name].is_flag or options[name].count)
            if takes_value and not value:
                i += 1
                assert i < len(rest), f"{name} without its value in {' '.join(args)!r}"
        else:
            positional += 1
        i += 1
    if {"-h", "--help"} & set(rest):
        return  # the help needs no arguments
    allowed = sum(p.nargs if p.nargs > 0 else 10**6 for p in arguments)
    needed = sum(p.nargs for p in arguments if p.required and p.nargs > 0)
    assert needed <= positional <= allowed, (
        f"{command.name} takes {needed}..{allowed} arguments, {' '.join(args)!r} gives "
        f"{positional}")


def all_commands(group=main, prefix=()):
    for name, command in group.commands.items():
        yield (*prefix, name), command
        if isinstance(command, click.Group):
            yield from all_commands(command, (*prefix, name))


def test_pages_exist():
    assert (ROOT / "CHANGELOG.md").exists()
    assert len(PAGES) >= 10


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_command_line_names_real_commands_and_options(page):
    count = 0
    for line_number, block in fenced_blocks(page, SHELL):
        for args in command_lines(block):
            try:
                check_command_line(args)
            except AssertionError as exc:
                raise AssertionError(f"{page.name}:{line_number}: {exc}") from None
            count += 1
    if page.name == "README.md":
        assert count >= 10


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_python_block_names_what_exists(page):
    for line_number, block in fenced_blocks(page, {"python"}):
        where = f"{page.name}:{line_number}"
        tree = ast.parse(block, filename=where)  # a SyntaxError fails the test
        aliases = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    importlib.import_module(alias.name)
                    aliases[alias.asname or alias.name.split(".")[0]] = alias.name
            elif isinstance(node, ast.ImportFrom):
                module = importlib.import_module(node.module)
                for alias in node.names:
                    assert hasattr(module, alias.name) or importlib.util.find_spec(
                        f"{node.module}.{alias.name}"), f"{where}: {node.module}.{alias.name}"
        for node in ast.walk(tree):
            chain = attribute_chain(node)
            if chain and chain[0] in aliases and aliases[chain[0]].startswith("vsmatch"):
                target = importlib.import_module(aliases[chain[0]])
                for name in chain[1:]:
                    assert hasattr(target, name), f"{where}: {'.'.join(chain)} does not exist"
                    target = getattr(target, name)


def attribute_chain(node) -> list[str] | None:
    """``a.b.c`` as ['a', 'b', 'c'] for the outermost attribute of a chain."""
    names = []
    while isinstance(node, ast.Attribute):
        names.append(node.attr)
        node = node.value
    if names and isinstance(node, ast.Name):
        return [node.id, *reversed(names)]
    return None


@pytest.mark.parametrize("path,command", [((), main), *all_commands()],
                         ids=lambda v: " ".join(v) or "vsmatch" if isinstance(v, tuple) else "")
def test_each_command_help_ends_with_examples_that_parse(path, command):
    result = click.testing.CliRunner().invoke(main, [*path, "--help"])
    assert result.exit_code == 0
    tail = result.output.rstrip().split("Examples:")
    assert len(tail) == 2, f"vsmatch {' '.join(path)} --help has no Examples block"
    lines = [line.strip() for line in tail[1].strip().splitlines()]
    assert 1 <= len(lines) <= 4
    for line in lines:
        words = shlex.split(line)
        assert words[:1 + len(path)] == ["vsmatch", *path], line
        check_command_line(words[1:])


def test_the_checker_catches_what_is_stale():
    for bad in (["rum", "a.png", "b.png"], ["run", "a.png", "b.png", "--max-disparity", "9"],
                ["run", "a.png"], ["datasets", "fetch"], ["eval", "--dataset"]):
        with pytest.raises(AssertionError):
            check_command_line(bad)
    check_command_line(["run", "a.png", "b.png", "--min-disp", "-40", "--max-disp=9", "-v"])
    assert list(command_lines("X=1 vsmatch demo && python -m vsmatch run a b  # c\n")) == [
        ["demo"], ["run", "a", "b"]]


@pytest.mark.parametrize("page", [*PAGES, *sorted((ROOT / "configs").glob("*.yaml"))],
                         ids=lambda p: p.name)
def test_no_user_facing_page_names_an_issue(page):
    found = re.findall(r"[Ii]ssues? \d+|#\d{1,3}\b", page.read_text(encoding="utf-8"))
    assert not found, f"{page.name}: {found[:5]}"


def test_the_readme_is_a_front_door():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 210
    for page in (ROOT / "docs").glob("*.md"):
        assert f"docs/{page.name}" in readme, f"README does not link docs/{page.name}"
    for marker in ("<!-- setup -->", "<!-- tests -->"):
        assert marker in readme  # .ci/run runs the blocks after these as written
    assert "<!-- setup -->" in (ROOT / ".ci" / "run").read_text()


def test_version_matches_the_changelog():
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    released = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", changelog, re.M)
    assert released and released[0] == vsmatch.__version__
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert f'version = "{vsmatch.__version__}"' in pyproject
    result = click.testing.CliRunner().invoke(main, ["--version"])
    assert vsmatch.__version__ in result.output


def test_the_generated_references_are_current():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "docs_reference.py"),
                           "--check"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_every_local_link_of_the_pages_exists():
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if "://" in target:
                continue
            assert (page.parent / target).exists(), f"{page.name}: link to {target}"
