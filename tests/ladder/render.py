"""Draw an LD body of a plc.xml as a picture (matplotlib), for docs/ladder.md.

Elements stand where the Editor's file puts them; wires follow the points the file stores.
Contacts `| |`, `|/|`, `|P|`, `|N|`; coils `( )`, `(/)`, `(S)`, `(R)`, `(P)`, `(N)`; blocks
as boxes with their pins; variables as rounded boxes. To redraw the picture of the docs:

    PYTHONPATH=harness:tests/ladder python tests/ladder/render.py tests/ladder/examples/sb1_button.xml docs/img/ladder-sb1.png
"""
from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyBboxPatch, Rectangle  # noqa: E402
from lxml import etree  # noqa: E402

from plclab.frontend.graphical import read_elements  # noqa: E402

NS = {"ppx": "http://www.plcopen.org/xml/tc6_0201"}


def render(xml: bytes, out: str, pou: str | None = None) -> None:
    root = etree.fromstring(xml)
    pous = root.findall("ppx:types/ppx:pous/ppx:pou", NS)
    el = next(p for p in pous if pou is None or p.get("name") == pou)
    body = el.find("ppx:body/ppx:LD", NS)
    if body is None:
        body = el.find("ppx:body/ppx:FBD", NS)
    elements = read_elements(body)
    sizes = {int(e.get("localId")): (float(e.get("width", 30)), float(e.get("height", 20))) for e in body
             if isinstance(e.tag, str) and e.get("localId")}
    max_y = max(e.y + sizes[e.local_id][1] for e in elements) + 20
    max_x = max(e.x + sizes[e.local_id][0] for e in elements) + 20
    fig, ax = plt.subplots(figsize=(max_x / 90, max_y / 90), dpi=110)
    ax.set_xlim(0, max_x)
    ax.set_ylim(max_y, 0)
    ax.axis("off")
    wire = dict(color="#1f4e79", lw=1.4)
    for w_el in body.iter(f"{{{NS['ppx']}}}connection"):
        pts = [(float(p.get("x")), float(p.get("y"))) for p in w_el.findall("ppx:position", NS)]
        if len(pts) >= 2:
            # orthogonal, as the Editor draws: horizontal from the source, then vertical, then in
            (x1, y1), (x0, y0) = pts[0], pts[-1]
            xm = x0 + 10 if abs(y1 - y0) > 0 else x1
            ax.plot([x0, xm, xm, x1], [y0, y0, y1, y1], **wire)
    for e in elements:
        w, h = sizes[e.local_id]
        x, y = e.x, e.y
        if e.kind in ("leftPowerRail", "rightPowerRail"):
            ax.add_patch(Rectangle((x, y), 4, h, color="#333333"))
        elif e.kind == "contact":
            mark = "/" if e.pin_in.negated else {"rising": "P", "falling": "N"}.get(e.pin_in.edge, "")
            ax.plot([x, x + 10], [y + 10, y + 10], **wire)
            ax.plot([x + 20, x + w], [y + 10, y + 10], **wire)
            ax.plot([x + 10, x + 10], [y, y + 20], color="black", lw=2)
            ax.plot([x + 20, x + 20], [y, y + 20], color="black", lw=2)
            ax.text(x + 15, y + 11, mark, ha="center", va="center", fontsize=8)
            ax.text(x + 15, y - 4, e.name, ha="center", va="bottom", fontsize=8)
        elif e.kind == "coil":
            mark = "/" if e.pin_in.negated else {"set": "S", "reset": "R"}.get(
                e.pin_in.storage, {"rising": "P", "falling": "N"}.get(e.pin_in.edge, ""))
            ax.text(x + 15, y + 10, f"( {mark} )" if mark else "(   )", ha="center", va="center", fontsize=11)
            ax.text(x + 15, y - 4, e.name, ha="center", va="bottom", fontsize=8)
        elif e.kind == "block":
            ax.add_patch(Rectangle((x, y), w, h, fill=False, lw=1.5))
            ax.text(x + w / 2, y + 12, e.type_name, ha="center", va="center", fontsize=8, weight="bold")
            if e.name:
                ax.text(x + w / 2, y - 4, e.name, ha="center", va="bottom", fontsize=8)
            for i, pin in enumerate(e.inputs):
                ax.text(x + 3, y + 30 + 20 * i, pin.param, ha="left", va="center", fontsize=7)
            for pin in e.outputs:
                if pin.rel is not None:
                    ax.text(x + w - 3, y + pin.rel[1], pin.param, ha="right", va="center", fontsize=7)
        elif e.kind in ("inVariable", "outVariable", "inOutVariable"):
            ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0,rounding_size=6", fill=False, lw=1))
            ax.text(x + w / 2, y + h / 2, e.name, ha="center", va="center", fontsize=7)
    fig.savefig(out, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    with open(sys.argv[1], "rb") as f:
        render(f.read(), sys.argv[2])
    print(f"wrote {sys.argv[2]}")
