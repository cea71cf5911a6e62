"""The notebooks' fixed prose, read from one Markdown file per notebook (``text/<notebook>.md``).

Self-check questions, exercise options and fixed notes are words, not code: a teacher edits them
in ``pusht/nb/text/`` without reading Python, and the modules that held them as strings load them
here under the same names (``SELF_CHECKS``, ``EX1_OPTIONS``, ...), which released notebooks and
the grader import. Sentences that read a run's numbers stay in Python, each guarded by a claim.

The grammar (``text/README.md`` says the same for teachers)::

    <!-- a comment: ignored, may span lines -->
    # Self-check: <name>
    <the question, a paragraph>
    - (a) <an option>
    - (b) <an option, wrapped over lines:
      an indent shows that a line continues it>
    Answer: b
    Why: <why, a paragraph>

    # Options: <name>
    - (a) <an option>

    # Note: <name>
    <a paragraph>

A line starting at its first column with ``# ``, ``- ``, ``Answer:`` or ``Why:`` starts a field;
any other line continues the field above it, joined with one space (so a wrapped line that would
begin with one of those is indented). A blank line or a comment ends a field. Options are lettered
a, b, c, ... in order. ``{{name}}`` is a value the loading module fills in (a number it formats
from its constants); a placeholder left unfilled, or a value given that no placeholder takes, is an
error. Any other departure raises ``ValueError`` naming the file and line: a notebook that cannot
read its words should stop at import, not show half a question.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from ..selfcheck import Question

TEXT = Path(__file__).with_name("text")
KINDS = ("Self-check", "Options", "Note")

_HEADING = re.compile(r"# (?P<kind>[^:]+): (?P<name>\w+)\s*$")
_OPTION = re.compile(r"- \((?P<letter>[a-z])\)(?P<text>.*)$")
_PLACEHOLDER = re.compile(r"\{\{(\w+)\}\}")


@dataclass
class Section:
    """One ``# Kind: name`` section; every field is ``(text, line)``, its text joined."""
    kind: str
    name: str
    line: int
    text: tuple | None = None                       # the question's or the note's paragraph
    options: dict = field(default_factory=dict)     # letter -> (text, line)
    answer: tuple | None = None
    why: tuple | None = None


class _Parser:
    def __init__(self, path: Path):
        self.path, self.sections, self.section = Path(path), {}, None
        self.open = None                            # the field a continuation line joins: [parts, ...]

    def fail(self, line: int, message: str):
        raise ValueError(f"{self.path}:{line}: {message}")

    def parse(self) -> dict:
        comment = False
        for n, raw in enumerate(self.path.read_text(encoding="utf-8").splitlines(), 1):
            line = raw.rstrip()
            if comment or line.startswith("<!--"):
                comment = "-->" not in line
                self.open = None
                continue
            if not line:
                self.open = None
            elif line.startswith("#"):
                self.heading(n, line)
            elif line.startswith("-"):
                self.option(n, line)
            elif line.startswith(("Answer:", "Why:")):
                self.marked(n, line)
            else:
                self.text(n, line)
        if comment:
            self.fail(n, "a comment opened with <!-- is never closed with -->")
        self.finish()
        return self.sections

    def heading(self, n: int, line: str):
        m = _HEADING.match(line)
        if not m:
            self.fail(n, f"a heading is '# <kind>: <name>' (kind one of {', '.join(KINDS)}; name letters, digits, "
                         "_); indent a wrapped line that starts with '#'")
        if m["kind"] not in KINDS:
            self.fail(n, f"unknown section {m['kind']!r}: a section is one of {', '.join(KINDS)}")
        key = (m["kind"], m["name"])
        if key in self.sections:
            self.fail(n, f"duplicate section '# {m['kind']}: {m['name']}' (first at line {self.sections[key].line})")
        self.finish()
        self.section = self.sections[key] = Section(m["kind"], m["name"], n)
        self.open = None

    def current(self, n: int, what: str) -> Section:
        if self.section is None:
            self.fail(n, f"{what} before the first section ('# Self-check: <name>', '# Options: <name>' or "
                         "'# Note: <name>')")
        return self.section

    def option(self, n: int, line: str):
        s = self.current(n, "an option")
        m = _OPTION.match(line)
        if not m:
            self.fail(n, "option without a letter: write '- (a) <text>' (indent a wrapped line that starts "
                         "with '-')")
        if not m["text"].strip():
            self.fail(n, f"option ({m['letter']}) has no text")
        if s.kind == "Note":
            self.fail(n, f"a Note holds one paragraph, not options ('# Note: {s.name}', line {s.line})")
        if s.kind == "Self-check" and s.text is None:
            self.fail(n, f"an option before the question of '# Self-check: {s.name}'")
        if s.answer is not None:
            self.fail(n, "an option after the Answer: line")
        expected = chr(ord("a") + len(s.options))
        if m["letter"] != expected:
            self.fail(n, f"option ({m['letter']}) where ({expected}) comes next: options are lettered a, b, c, "
                         "... in order")
        parts = [m["text"].strip()]
        s.options[m["letter"]] = (parts, n)
        self.open = parts

    def marked(self, n: int, line: str):
        s = self.current(n, line.split(":", 1)[0])
        key, value = (x.strip() for x in line.split(":", 1))
        if s.kind != "Self-check":
            self.fail(n, f"{key}: belongs to a Self-check, not to '# {s.kind}: {s.name}'")
        if key == "Answer":
            if not s.options or s.answer is not None:
                self.fail(n, "Answer: comes once, after the options")
            if not re.fullmatch(r"[a-z]", value):
                self.fail(n, f"Answer: is one letter, got {value!r}")
            if value not in s.options:
                self.fail(n, f"the answer ({value}) is not among the options ({', '.join(s.options)})")
            s.answer, self.open = (value, n), None
        else:
            if s.answer is None or s.why is not None:
                self.fail(n, "Why: comes once, after the Answer: line")
            if not value:
                self.fail(n, "Why: needs its text on the same line")
            s.why = ([value], n)
            self.open = s.why[0]

    def text(self, n: int, line: str):
        s = self.current(n, "text")
        if self.open is not None:
            self.open.append(line.strip())
        elif s.kind == "Options":
            self.fail(n, f"text in '# Options: {s.name}', which holds only options ('- (a) <text>')")
        elif s.text is not None:
            self.fail(n, "text outside a field: a paragraph does not continue after a blank line, and a "
                         "line with no marker ('- (a)', 'Answer:', 'Why:') starts nothing here")
        else:
            s.text = ([line.strip()], n)
            self.open = s.text[0]

    def finish(self):
        """The section just read must be whole; its fields' lines are joined with single spaces."""
        s = self.section
        if s is None:
            return
        where = f"'# {s.kind}: {s.name}' (line {s.line})"
        need = {"Self-check": [("text", "no question"), ("options", "no options"), ("answer", "no Answer: line"),
                               ("why", "no Why: line")],
                "Options": [("options", "no options")], "Note": [("text", "no text")]}[s.kind]
        for attr, missing in need:
            if not getattr(s, attr):
                self.fail(s.line, f"{where} has {missing}")
        if s.kind != "Note" and len(s.options) < 2:
            self.fail(s.line, f"{where} has fewer than two options")
        join = " ".join
        s.text = s.text and (join(s.text[0]), s.text[1])
        s.why = s.why and (join(s.why[0]), s.why[1])
        s.options = {k: (join(parts), n) for k, (parts, n) in s.options.items()}
        self.section = None


@lru_cache(maxsize=None)
def parse(path: Path) -> dict:
    """``{(kind, name): Section}`` of one prose file, checked whole (read once per process)."""
    return _Parser(path).parse()


def _path(notebook: str) -> Path:
    return TEXT / f"{notebook}.md"


def _section(path: Path, kind: str, name: str) -> Section:
    try:
        return parse(path)[kind, name]
    except KeyError:
        raise ValueError(f"{path}: no section '# {kind}: {name}'") from None


def _fill(path: Path, s: Section, fields: dict, values: dict) -> dict:
    """``fields`` (``key -> (text, line)``) with every ``{{name}}`` replaced by ``values[name]``."""
    used = set()

    def one(text: str, line: int) -> str:
        def value(m):
            if m[1] not in values:
                raise ValueError(f"{path}:{line}: {{{{{m[1]}}}}} has no value: the notebook's module fills in "
                                 f"{', '.join('{{%s}}' % v for v in sorted(values)) or 'no value'} here")
            used.add(m[1])
            return str(values[m[1]])
        return _PLACEHOLDER.sub(value, text)

    out = {k: one(*f) for k, f in fields.items()}
    if set(values) - used:
        raise ValueError(f"{path}:{s.line}: '# {s.kind}: {s.name}' has no placeholder for "
                         f"{sorted(set(values) - used)}")
    return out


def self_checks(notebook: str, path: Path | None = None) -> dict[str, Question]:
    """A notebook's self-check questions, ``{name: Question}`` in the file's order."""
    path = path or _path(notebook)
    out = {}
    for (kind, name), s in parse(path).items():
        if kind == "Self-check":
            f = _fill(path, s, {"text": s.text, "why": s.why, **s.options}, {})
            out[name] = Question(text=f.pop("text"), options={k: f[k] for k in s.options}, answer=s.answer[0],
                                 why=f["why"])
    return out


def options(notebook: str, name: str, path: Path | None = None, **values) -> dict[str, str]:
    """The options ``{letter: text}`` of section ``# Options: <name>``, placeholders filled."""
    path = path or _path(notebook)
    s = _section(path, "Options", name)
    return _fill(path, s, s.options, values)


def note(notebook: str, name: str, path: Path | None = None, **values) -> str:
    """The paragraph of section ``# Note: <name>``, placeholders filled."""
    path = path or _path(notebook)
    s = _section(path, "Note", name)
    return _fill(path, s, {"text": s.text}, values)["text"]
