"""Runs every ```sh and ```python block of README.md, docs/*.md and
examples/README.md (a block in another language, such as a MATLAB call,
must be marked not run), and checks that every relative link in them leads
to a file, and every #anchor to a heading, that exists.

A block runs as a user would paste it: from the repository root, sh blocks
with bash (stopping at the first failing command, `tdvass` on the PATH from
<target>/release), python blocks with this test's interpreter. A block may
be left out only by an HTML comment right before it that says why:
``<!-- not run: REASON -->``. Files a block writes into the repository root
are removed afterwards, and the built FMUs in <target>/fmu are restored if a
block rebuilt them (the quick start builds the host platform only), so the
tests after this one see what tests/run_all.sh built.

Needs the FMU and the CLI built (tests/run_all.sh builds both before pytest).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCUMENTS = ("README.md", *sorted(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md")), "examples/README.md")
FENCE = re.compile(r"^```(\w+)[^\n]*\n(.*?)^```\s*$", re.MULTILINE | re.DOTALL)
NOT_RUN = re.compile(r"<!--\s*not run:\s*(.*?)\s*-->\s*$", re.DOTALL)
RUNNABLE = {"sh", "bash", "python"}
# Entries of the repository root that blocks may use and must never be removed.
KEEP = {"target", ".venv", ".git", "out"}


def _target_dir() -> Path:
    env = os.environ.get("CARGO_TARGET_DIR")
    path = Path(env) if env else ROOT / "target"
    return path if path.is_absolute() else ROOT / path


def blocks():
    """(document, line, language, code, reason-not-run or None) for every fenced block."""
    found = []
    for document in DOCUMENTS:
        text = (ROOT / document).read_text(encoding="utf-8")
        for match in FENCE.finditer(text):
            language, code = match.group(1), match.group(2)
            before = text[: match.start()].rstrip()
            marker = NOT_RUN.search(before[-400:])
            reason = marker.group(1) if marker and before.endswith("-->") else None
            line = text.count("\n", 0, match.start()) + 1
            found.append((document, line, language, code, reason))
    return found


LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation other than
    hyphens and underscores dropped, spaces to hyphens."""
    text = re.sub(r"[`*]", "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    return {_anchor(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", text, re.MULTILINE)}


def test_every_relative_link_leads_somewhere():
    broken = []
    for document in DOCUMENTS:
        source = ROOT / document
        text = FENCE.sub("", source.read_text(encoding="utf-8"))
        for target in LINK.findall(text):
            if re.match(r"[a-z]+:", target):
                continue  # https:, mailto:
            path, _, anchor = target.partition("#")
            resolved = (source.parent / path).resolve() if path else source
            if not resolved.exists():
                broken.append(f"{document}: {target} (no {path})")
            elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
                broken.append(f"{document}: {target} (no heading #{anchor} in {resolved.relative_to(ROOT)})")
    assert not broken, "broken links:\n" + "\n".join(broken)


def test_every_block_is_found_and_every_skip_has_a_reason():
    found = blocks()
    assert len(found) >= 10, f"only {len(found)} code blocks found"
    for document, line, language, _, reason in found:
        assert language in RUNNABLE or reason is not None, (
            f"{document}:{line}: a ```{language} block cannot be run here; mark it <!-- not run: REASON -->"
        )
        if reason is not None:
            assert len(reason) > 10, f"{document}:{line}: the reason for not running is too short"


@pytest.mark.parametrize("document,line,language,code,reason", blocks(),
                         ids=[f"{d}:{n}" for d, n, *_ in blocks()])
def test_block_runs(document, line, language, code, reason, tmp_path):
    if reason is not None:
        pytest.skip(f"marked not run in {document}: {reason}")
    release = _target_dir() / "release"
    fmu = Path(os.environ.get("TDVASS_FMU") or _target_dir() / "fmu" / "tdvass.fmu")
    if not (release / "tdvass").is_file() or not fmu.is_file():
        pytest.fail("build the CLI and the FMU first (cargo build --release; cargo run --release -p fmu-build)")
    env = dict(os.environ)
    env["PATH"] = f"{release}{os.pathsep}{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    script = tmp_path / ("block.py" if language == "python" else "block.sh")
    script.write_text(code, encoding="utf-8")
    command = [sys.executable, str(script)] if language == "python" else ["bash", "-eo", "pipefail", str(script)]
    before = {p.name for p in ROOT.iterdir()}
    built = {path: path.read_bytes() for path in (_target_dir() / "fmu").glob("*.fmu")}
    try:
        proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=900)
    finally:
        for entry in ROOT.iterdir():
            if entry.name not in before and entry.name not in KEEP:
                shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
        for path, content in built.items():
            if not path.is_file() or path.read_bytes() != content:
                path.write_bytes(content)
    assert proc.returncode == 0, (
        f"{document}:{line} ({language}) failed with status {proc.returncode}\n"
        f"--- block ---\n{code}\n--- stdout ---\n{proc.stdout[-3000:]}\n--- stderr ---\n{proc.stderr[-3000:]}"
    )
