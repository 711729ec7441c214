"""The icon of both FMUs (model.png in FMI 2.0, terminalsAndIcons/icon.png in
FMI 3.0) and the diagram of their documentation: the committed picture
fmu-build/assets/icon.png that tools/draw_icon.py draws, shown by
documentation/index.html beside it with the legend of its symbols."""

from __future__ import annotations

import html.parser
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmu_helpers import REPO_ROOT, fmu_path

ICON = REPO_ROOT / "fmu-build" / "assets" / "icon.png"
SCRIPT = REPO_ROOT / "tools" / "draw_icon.py"
ICON_ENTRY = {"tdvass.fmu": "model.png", "tdvass-fmi3.fmu": "terminalsAndIcons/icon.png"}
SYMBOLS = ["m_s", "k_s, c_s", "m_h", "k_h, c_h", "m_t", "k_t", "x_g", "x_s, x_h, x_t", "g e^(-tau s)",
           "u = g x_t(t - tau)"]


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", "not a PNG"
    return struct.unpack(">II", data[16:24])


@pytest.fixture(scope="module", params=list(ICON_ENTRY))
def fmu(request) -> zipfile.ZipFile:
    path = fmu_path().with_name(request.param)
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return zipfile.ZipFile(path)


def test_the_committed_icon_is_a_modest_square_png():
    data = ICON.read_bytes()
    assert png_size(data) == (320, 320)
    assert len(data) < 64_000


def test_the_fmu_carries_the_icon_and_the_diagram(fmu):
    icon = ICON.read_bytes()
    assert fmu.read(ICON_ENTRY[Path(fmu.filename).name]) == icon
    assert fmu.read("documentation/diagram.png") == icon
    # FMI 2.0 has no terminalsAndIcons folder, FMI 3.0 no model.png.
    other = {"model.png", "terminalsAndIcons/icon.png"} - {ICON_ENTRY[Path(fmu.filename).name]}
    assert not other & set(fmu.namelist())


class Page(html.parser.HTMLParser):
    """The images and table cells of a page."""

    def __init__(self):
        super().__init__()
        self.images: list[dict] = []
        self.cells: list[str] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.images.append(dict(attrs))
        elif tag == "td":
            self._cell = []

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self.cells.append("".join(self._cell))
            self._cell = None


def test_the_documentation_shows_the_diagram_with_its_legend(fmu):
    page = Page()
    page.feed(fmu.read("documentation/index.html").decode("utf-8"))
    assert len(page.images) == 1
    image = page.images[0]
    # A relative reference to the file beside the page, at its own size.
    assert image["src"] == "diagram.png" and f"documentation/{image['src']}" in fmu.namelist()
    assert (int(image["width"]), int(image["height"])) == png_size(ICON.read_bytes())
    assert "u = g x_t(t - tau)" in image["alt"]
    for symbol in SYMBOLS:
        assert symbol in page.cells, f"the legend lacks {symbol}"
    legend = page.cells[page.cells.index("m_s"):]
    assert "m_s (start 345 kg)" in legend[2]


def test_the_script_draws_the_same_picture_twice(tmp_path):
    """tools/draw_icon.py is deterministic (no time stamp, no software tag)
    and draws a picture of the committed one's size."""
    outputs = []
    for name in ("a.png", "b.png"):
        out = tmp_path / name
        subprocess.run([sys.executable, str(SCRIPT), str(out)], check=True, capture_output=True, timeout=120)
        outputs.append(out.read_bytes())
    assert outputs[0] == outputs[1]
    assert png_size(outputs[0]) == png_size(ICON.read_bytes())
    assert b"tEXtSoftware" not in outputs[0] and b"tIME" not in outputs[0]
