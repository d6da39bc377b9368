"""The documentation keeps up with the code.

- every hook of :mod:`regopack.registry.hookspecs` has a section in the plugin guide;
- every field of every built-in plugin's config model, and of the core scene
  models, has a description and is named in the scene format reference, in the
  section of its plugin or model;
- every relative link in the Markdown documentation points to a file (and, for
  links into Markdown files, to a heading) that exists;
- every hook's section in the plugin guide has an example;
- every command of the command line has a section in the CLI reference showing
  its current usage.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest
from pydantic import BaseModel

from regopack.cli.commands import build_parser
from regopack.registry import hookspecs
from regopack.registry.manager import default_registry
from regopack.registry.plugin_types import KINDS
from regopack.scenes.model import Domain, Outputs, Phase, PluginRef, Scene, Tiles

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PLUGIN_GUIDE = DOCS / "plugins" / "writing-plugins.md"
SCENE_FORMAT = DOCS / "reference" / "scene-format.md"
CLI_REFERENCE = DOCS / "reference" / "cli.md"

CORE_MODELS: dict[type[BaseModel], str] = {
    Scene: "Top level",
    Domain: "`[domain]`",
    PluginRef: "Plugin sections",
    Phase: "`[[phases]]`",
    Outputs: "`[outputs]`",
    Tiles: "`[tiles]`",
}
"""Core scene models and a text that the heading of their section contains."""

FENCE = re.compile(r"^(```|~~~).*?^\1\s*$", re.S | re.M)
INLINE_CODE = re.compile(r"`[^`\n]*`")
INLINE_LINK = re.compile(r"!?\[[^\]\n]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE_LINK = re.compile(r"^\s*\[[^\]\n]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$", re.M)
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$", re.M)


def markdown_files() -> list[Path]:
    files = sorted(DOCS.rglob("*.md"))
    files += [p for p in (ROOT / "README.md", ROOT / "CHANGELOG.md") if p.exists()]
    return files


def strip_code(text: str) -> str:
    """Text without fenced code blocks (lines kept) and inline code."""
    text = FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    return INLINE_CODE.sub("", text)


def sections(text: str) -> list[tuple[str, str]]:
    """``(heading, body)`` of every heading, the body running to the next heading of
    the same or a higher level (so it includes sub-sections)."""
    text = FENCE.sub(lambda m: m.group(0).replace("#", "\\#"), text)
    heads = [(m.start(), m.end(), len(m.group(1)), m.group(2)) for m in HEADING.finditer(text)]
    out = []
    for i, (_, end, level, title) in enumerate(heads):
        stop = len(text)
        for start2, _, level2, _ in heads[i + 1 :]:
            if level2 <= level:
                stop = start2
                break
        out.append((title, text[end:stop]))
    return out


def section(text: str, marker: str) -> str | None:
    """Body of the first section whose heading contains ``marker``."""
    for title, body in sections(text):
        if marker in title:
            return body
    return None


def slug(heading: str) -> str:
    """The anchor a Markdown renderer (GitHub's rules) gives a heading."""
    text = heading.strip().lower().replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    for title, _ in sections(path.read_text(encoding="utf-8")):
        base = slug(title)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def model_fields(model: type[BaseModel]) -> list[tuple[str, str | None]]:
    return [(name, info.description) for name, info in model.model_fields.items()]


# ---------------------------------------------------------------------------
# (a) hooks


def hook_names() -> list[str]:
    return sorted(
        name
        for name in dir(hookspecs)
        if name.startswith("regopack_") and hasattr(getattr(hookspecs, name), "regopack_spec")
    )


def test_there_are_hooks() -> None:
    assert len(hook_names()) >= 5


@pytest.mark.parametrize("hook", hook_names())
def test_every_hook_has_a_section_in_the_plugin_guide(hook: str) -> None:
    text = PLUGIN_GUIDE.read_text(encoding="utf-8")
    body = section(text, f"`{hook}`")
    assert body is not None, (
        f"{hook} is not documented: {PLUGIN_GUIDE.relative_to(ROOT)} needs a heading "
        f"containing `{hook}`"
    )
    assert body.strip(), f"the section of {hook} in the plugin guide is empty"


@pytest.mark.parametrize("hook", hook_names())
def test_every_hook_section_has_an_example(hook: str) -> None:
    """An example is a code block in the section or a link to one of the guide's headings."""
    text = PLUGIN_GUIDE.read_text(encoding="utf-8")
    body = section(text, f"`{hook}`") or ""
    links = [t.removeprefix("#") for t in INLINE_LINK.findall(body) if t.startswith("#")]
    has_code = FENCE.search(body) is not None
    assert has_code or any(a in anchors(PLUGIN_GUIDE) for a in links), (
        f"the section of {hook} in the plugin guide has no example (a code block or a link "
        "to an example in the guide)"
    )


# ---------------------------------------------------------------------------
# (b) config fields


def plugin_models() -> list[tuple[str, str, type[BaseModel]]]:
    registry = default_registry(autoload=False)
    return [
        (kind, name, registry.get(kind, name).config_model)
        for kind in KINDS
        for name in registry.names(kind)
    ]


def test_there_are_plugins() -> None:
    kinds = {kind for kind, _, _ in plugin_models()}
    assert {"size", "shape", "insertion", "density"} <= kinds


def test_every_plugin_field_is_described_and_documented() -> None:
    # a plugin's section may live in the scene format page or in its own reference page
    pages = [
        SCENE_FORMAT,
        *sorted(p for p in (DOCS / "reference").glob("*.md") if p != SCENE_FORMAT),
    ]
    text = "\n".join(p.read_text(encoding="utf-8") for p in pages)
    problems = []
    for kind, name, model in plugin_models():
        body = section(text, f"`{name}`")
        if body is None:
            problems.append(f"{kind} plugin {name!r} has no section (a heading with `{name}`)")
            continue
        for field, description in model_fields(model):
            if not (description and description.strip()):
                problems.append(f"{kind} plugin {name!r}: field {field!r} has no description")
            if f"`{field}`" not in body:
                problems.append(f"{kind} plugin {name!r}: field `{field}` is not in its section")
    assert not problems, "docs/reference:\n" + "\n".join(problems)


@pytest.mark.parametrize("model", list(CORE_MODELS), ids=lambda m: m.__name__)
def test_every_core_scene_field_is_described_and_documented(model: type[BaseModel]) -> None:
    text = SCENE_FORMAT.read_text(encoding="utf-8")
    marker = CORE_MODELS[model]
    body = section(text, marker)
    assert body is not None, f"no section with {marker!r} in its heading"
    problems = []
    for field, description in model_fields(model):
        if not (description and description.strip()):
            problems.append(f"{model.__name__}.{field} has no description")
        if f"`{field}`" not in body:
            problems.append(f"{model.__name__}.{field} is not in the section {marker!r}")
    assert not problems, "\n".join(problems)


# ---------------------------------------------------------------------------
# (c) command line


def subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


def test_there_are_commands() -> None:
    assert {"run", "plugins", "schema"} <= set(subcommands())


@pytest.mark.parametrize("command", list(subcommands()))
def test_every_command_is_in_the_cli_reference(command: str, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "80")  # argparse wraps the usage to the terminal's width
    text = CLI_REFERENCE.read_text(encoding="utf-8")
    body = section(text, f"`regopack {command}`")
    assert body is not None, f"{CLI_REFERENCE.name} needs a heading `regopack {command}`"
    usage = subcommands()[command].format_usage().strip()
    assert usage in body, f"the usage of regopack {command} changed; it is now:\n{usage}"


def test_the_cli_reference_shows_the_current_help(monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    assert build_parser().format_help().strip() in CLI_REFERENCE.read_text(encoding="utf-8")


# ---------------------------------------------------------------------------
# (d) links


def relative_links(path: Path) -> list[str]:
    text = strip_code(path.read_text(encoding="utf-8"))
    targets = INLINE_LINK.findall(text) + REFERENCE_LINK.findall(text)
    return [t for t in targets if not re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", t)]


@pytest.mark.parametrize("path", markdown_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_point_to_existing_files(path: Path) -> None:
    problems = []
    for target in relative_links(path):
        file_part, _, fragment = target.partition("#")
        dest = (path.parent / file_part).resolve() if file_part else path
        if not dest.exists():
            problems.append(f"{target}: no such file")
        elif fragment and dest.suffix == ".md" and fragment not in anchors(dest):
            problems.append(f"{target}: no heading with the anchor #{fragment}")
    assert not problems, f"{path.relative_to(ROOT)}:\n" + "\n".join(problems)


def test_the_link_checker_finds_links(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "# Title\n[a](missing.md) ![b](img.png) [c](https://example.org) [d](#title)\n"
        "`[e](in-code.md)`\n```\n[f](in-fence.md)\n```\n[g]: other.md\n",
        encoding="utf-8",
    )
    assert relative_links(page) == ["missing.md", "img.png", "#title", "other.md"]
    assert anchors(page) == {"title"}


def test_slugs() -> None:
    assert slug("`regopack run`") == "regopack-run"
    assert slug("Shapes (plugin `octagon`)") == "shapes-plugin-octagon"
    assert slug("The packing control coefficient η (plugin `eta`)") == (
        "the-packing-control-coefficient-η-plugin-eta"
    )
