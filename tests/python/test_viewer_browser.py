"""The viewer page (issue 38) in a real browser: headless Chromium opens the index.html that
`lambert run` writes, from file:// with no network, and its screenshots are compared with the
run's own PNG and with each other (linearity of the light sliders). The page's state comes
from the URL's fragment (#ev=..&w1=..&ui=0), the same state its sliders write.

Skipped, saying so, where Chromium is missing (scripts/setup.sh installs it; CI has it)."""
import json
import os
import shutil
import subprocess

import numpy as np
import pytest

from conftest import run_cli

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="Chromium is not installed (apt install chromium): the viewer "
    "page's browser test cannot run")

SIZE = 512  # the Cornell camera's image size: the screenshot and the PNG share pixels
VIRIDIS = [(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 140),
           (39, 173, 129), (92, 200, 99), (170, 220, 50), (253, 231, 37)]  # as viewer.js


def png(path):
    import matplotlib.image
    return matplotlib.image.imread(str(path))[..., :3].astype(float)


def chromium(tmp_path, url, *, screenshot=None, dump_dom=False):
    """Headless Chromium on `url` (software WebGL, a fresh profile, 10 s of virtual time so the
    page finishes loading before the capture)."""
    args = [CHROMIUM, "--headless", "--no-sandbox", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", "--hide-scrollbars", "--no-first-run",
            "--disable-background-networking", f"--user-data-dir={tmp_path / 'profile'}",
            "--virtual-time-budget=10000", f"--window-size={SIZE},{SIZE}"]
    args += [f"--screenshot={screenshot}"] if screenshot else ["--dump-dom"]
    p = subprocess.run(args + [url], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    return p.stdout


def blocks(image, n=8):
    """Means of n x n blocks of an image (SIZE x SIZE x 3): averages the 8-bit quantisation
    and the edge pixels where two rasterisers differ."""
    b = SIZE // n
    return image.reshape(n, b, n, b, 3).mean(axis=(1, 3))


def linear(srgb):
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


@pytest.fixture(scope="module")
def cornell_run(tmp_path_factory):
    """The Cornell box lit by three sources of comparable power (0.1-0.4 MW): its light, the
    tall block glowing red, a bluish sky through the open front."""
    out = tmp_path_factory.mktemp("viewer") / "out"
    run_cli("run", "-o", out, "--patches", 400, "--sky", "0.3,0.3,0.4", "--emit",
            "tall_block=0.5,0.1,0.1", "-q")
    report = json.loads((out / "report.json").read_text())
    return out, report


def shot(tmp_path, out, fragment, name):
    path = tmp_path / f"{name}.png"
    chromium(tmp_path, f"file://{out / 'index.html'}#ui=0&{fragment}", screenshot=path)
    image = png(path)
    assert image.shape == (SIZE, SIZE, 3)
    return image


def test_the_page_loads_offline_and_draws_what_the_run_rendered(cornell_run, tmp_path):
    out, report = cornell_run
    html = (out / "index.html").read_text()
    # Nothing to fetch: no script, stylesheet or image from elsewhere.
    for attribute in ("src=", "href="):
        assert f'{attribute}"http' not in html and f"{attribute}'http" not in html
    dom = chromium(tmp_path, f"file://{out / 'index.html'}")
    assert 'data-state="ready"' in dom, dom[-2000:]
    assert "tall_block" in dom and "sky" in dom  # one slider per light source

    # The camera file's view at the run's exposure: the screenshot is the run's PNG up to how
    # the two rasterisers differ (the page splits each quad into two linearly interpolated
    # triangles where lambert interpolates bilinearly; MSAA edges vs 2 x 2 supersampling).
    # Measured: 8 x 8 block means within 0.005 (of 1) of the PNG's; 0.03 allows for other
    # GPUs and drivers and still catches a wrong camera, exposure or tone curve (each moves
    # blocks by 0.1 or more).
    viewer = blocks(shot(tmp_path, out, "", "default"))
    rendered = blocks(png(out / "cornell.png"))
    assert np.abs(viewer - rendered).max() < 0.03
    # The red wall on the left, the green one on the right (the Cornell camera's view; the
    # bluish sky and the red glow tint them).
    left, right = viewer[2:6, 0], viewer[2:6, 7]
    assert (left[:, 0] > left[:, 1] + 0.1).all(), left
    assert (right[:, 1] > right[:, 0] + 0.1).all(), right


def test_the_light_sliders_relight_by_linearity(cornell_run, tmp_path):
    out, report = cornell_run
    sources = report["viewer"]["light_sources"]
    assert len(sources) == 3
    ev = report["render"]["exposure_ev"] - 2  # two stops down: only the lamp clips
    full_srgb = shot(tmp_path, out, f"ev={ev:.2f}", "full")
    full = blocks(linear(full_srgb))
    first_off = blocks(linear(shot(tmp_path, out, f"ev={ev:.2f}&w1=0", "first_off")))
    first_only = blocks(linear(shot(tmp_path, out, f"ev={ev:.2f}&w2=0&w3=0", "first_only")))
    halved = blocks(linear(shot(tmp_path, out, f"ev={ev:.2f}&w1=0.5&w2=0.5&w3=0.5", "half")))
    # Blocks with a clipped pixel (the lamp) are not linear in anything; the rest must be.
    clipped = (full_srgb.max(axis=2) >= 0.99).reshape(8, SIZE // 8, 8, SIZE // 8).any(axis=(1, 3))
    assert clipped.sum() <= 4
    # Radiance is linear in the intensities: the first source alone plus the others alone is
    # all of them, and halving every intensity halves the picture. Per block (4096 pixels),
    # 8-bit quantisation averages to < 1e-3 in linear units, and MSAA resolves edges in sRGB
    # (not linearly: up to ~1 % of a block with edges); measured 4.4e-4 at most.
    tolerance = 0.01 * full + 2e-3
    ok = ~clipped[..., None]
    assert ((np.abs(first_off + first_only - full) <= tolerance) | ~ok).all()
    assert ((np.abs(2 * halved - full) <= 2 * tolerance) | ~ok).all()
    # The slider moved the picture: the first source's share is large.
    assert first_only.sum() > 0.1 * full.sum()


def test_patch_edges_and_false_colour(cornell_run, tmp_path):
    out, report = cornell_run
    picture = shot(tmp_path, out, "", "picture")
    edges = shot(tmp_path, out, "edges=1", "edges")
    # The patch edges draw dark lines over the walls: 402 patches' edges, a few percent of
    # the pixels (measured: the mean drops by 0.026 of 1).
    assert edges.mean() < picture.mean() - 0.01
    # False colour: the pixels are viridis colours (within 0.03 of the ramp's 256, 8-bit
    # rounding and the ramp's linear filtering between them; edge pixels blend two colours).
    # The black background around the box is not the scene.
    false = shot(tmp_path, out, "mode=radiosity", "false").reshape(-1, 3)
    false = false[false.max(axis=1) > 0.1]
    stops = np.array(VIRIDIS) / 255.0
    ramp = np.concatenate([stops[k] + (stops[k + 1] - stops[k]) * t[:, None]
                           for k in range(len(stops) - 1) for t in [np.linspace(0, 1, 32)]])
    distance = np.sqrt(((false[::7, None, :] - ramp[None]) ** 2).sum(axis=2)).min(axis=1)
    assert (distance < 0.03).mean() > 0.97


def test_a_heat_page_opens_on_the_temperature_in_false_colour(tmp_path):
    """`lambert heat --glb` (the thermal box): the page is ready, opens on the temperature
    (no #mode given) and draws it in viridis with the colour bar; the hot heater (800 K) is
    the ramp's top, yellow, and the cold plate (300 K) its bottom, purple."""
    root = os.path.join(os.path.dirname(__file__), "..", "..", "data", "thermal_box")
    out = tmp_path / "heat"
    run_cli("heat", os.path.join(root, "thermal_box.stl"), "--surfaces",
            os.path.join(root, "surfaces.json"), "--length-unit", "mm", "--patches", 200, "-q",
            "-o", f"{out}/", "--glb", out / "h.glb")
    dom = chromium(tmp_path, f"file://{out / 'h.html'}")
    assert 'data-state="ready"' in dom, dom[-2000:]
    path = tmp_path / "heat.png"
    chromium(tmp_path, f"file://{out / 'h.html'}#ui=0", screenshot=path)
    pixels = png(path).reshape(-1, 3)
    pixels = pixels[pixels.max(axis=1) > 0.1]  # the scene, not the black background
    stops = np.array(VIRIDIS) / 255.0
    ramp = np.concatenate([stops[k] + (stops[k + 1] - stops[k]) * t[:, None]
                           for k in range(len(stops) - 1) for t in [np.linspace(0, 1, 32)]])
    distance = np.sqrt(((pixels[::7, None, :] - ramp[None]) ** 2).sum(axis=2)).min(axis=1)
    # Viridis throughout (8-bit rounding and edge blending: as the radiosity test above),
    # and both ends of the ramp present: the heater's yellow and the cold plate's purple.
    assert (distance < 0.03).mean() > 0.97
    assert (np.abs(pixels - stops[-1]).max(axis=1) < 0.03).any()
    assert (np.abs(pixels - stops[0]).max(axis=1) < 0.03).any()
