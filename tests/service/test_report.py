"""What a browser shows of the files a designer takes away: every type's SVG drawing and its
design report (POST /v1/report), rendered in Chromium. Every label lies inside its sheet and
overlaps no other; the report asks nothing of any site (each request the page makes is
recorded)."""

from __future__ import annotations

import itertools
import re

import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app

from ..support.designs import random_designs
from .test_browser import ARGS, CHROMIUM

TYPES = synth.mechanisms.all_types()
LOAD = {"length_unit": "mm", "crank_rpm": 30.0, "cutting_force": 3000.0, "slider_mass": 40.0}
SLACK = 0.5  # px: boxes that share no more than this are apart (a glyph's rounding)

# each svg's box and its texts' boxes, as the browser laid them out
BOXES = """() => [...document.querySelectorAll("svg")]
  .filter((s) => !s.parentElement.closest("svg"))
  .map((s) => {
    const box = (e) => {
      const b = e.getBoundingClientRect();
      return [b.left, b.top, b.right, b.bottom];
    };
    const texts = [...s.querySelectorAll("text")];
    return { sheet: box(s), texts: texts.map((t) => ({ text: t.textContent, box: box(t) })) };
  })"""


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM:
        pytest.skip("no Chromium (tests/service/test_browser.py says how to install it)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


def fitted(svg: str, width: int = 1000) -> str:
    """An SVG document as a viewer shows it zoomed to fit ``width`` pixels (its true size may
    set its words smaller than a browser's least font size)."""
    body = re.sub(r"^<\?xml[^>]*>\s*", "", svg)
    body = re.sub(r'width="[^"]*mm" height="[^"]*mm"', f'width="{width}"', body, count=1)
    return f"<!doctype html><html><body style='margin:0'>{body}</body></html>"


def rendered(browser, html: str, width: int = 1280) -> tuple[list[dict], list[str]]:
    """The page's sheets (``BOXES``) and every URL it requested."""
    page = browser.new_page(viewport={"width": width, "height": 900})
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    try:
        page.set_content(html, wait_until="load")
        return page.evaluate(BOXES), requests
    finally:
        page.close()


def assert_labels_apart(sheets: list[dict]) -> None:
    for s in sheets:
        x0, y0, x1, y1 = s["sheet"]
        for t in s["texts"]:
            a, b, c, d = t["box"]
            inside = a >= x0 - SLACK and b >= y0 - SLACK and c <= x1 + SLACK and d <= y1 + SLACK
            assert inside, f"{t['text']!r} at {t['box']} leaves its sheet {s['sheet']}"
        for t, u in itertools.combinations(s["texts"], 2):
            (a, b, c, d), (e, f, g, h) = t["box"], u["box"]
            w, v = min(c, g) - max(a, e), min(d, h) - max(b, f)
            assert w <= SLACK or v <= SLACK, f"{t['text']!r} and {u['text']!r} overlap"


@pytest.mark.parametrize("mtype", TYPES)
def test_every_types_drawing_keeps_its_labels_apart_and_on_the_sheet(browser, mtype):
    for p in random_designs(mtype, 3, seed=43):
        for angle in (None, 0.0, 137.0):
            doc = synth.export(mtype, p, "svg", angle).decode()
            sheets, _ = rendered(browser, fitted(doc))
            assert len(sheets) == 1 and len(sheets[0]["texts"]) > 2
            assert_labels_apart(sheets)


@pytest.mark.parametrize("width", [1280, 390])
@pytest.mark.parametrize("mtype", TYPES)
def test_every_types_report_keeps_its_labels_apart_and_asks_no_site(browser, client, mtype, width):
    (p,) = random_designs(mtype, 1, seed=47)
    load = LOAD if synth.mechanisms.get(mtype).frame is not None else None
    body = {"mechanism": {"type": mtype, "params": p}, "targets": {"bound_deg": 20.0}}
    r = client.post("/v1/report", json={**body, **({"load": load} if load else {})})
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    sheets, requests = rendered(browser, r.text, width)
    assert len(sheets) >= 5  # the drawing and the charts
    assert_labels_apart(sheets)
    assert requests == [], f"the report asked for {requests}"
