"""The scene out of Python: one self-contained HTML file (Meshcat's browser client inlined, the
scene's commands packed as that client expects them, replayed in order: no server, no network), or a
live Meshcat server; and the small pictures the scene carries (colour bar, joint labels)."""

from __future__ import annotations

import base64
import html as _html
import io
import json
from pathlib import Path

import numpy as np

from ..extras import optional
from . import three
from .colors import CABLE_MAP, tension_rgb
from .three import Command


def meshcat_dist() -> Path:
    meshcat = optional("meshcat", "the viewer")

    return Path(meshcat.__file__).parent / "viewer" / "dist"


def scene_html(scene) -> str:
    """One self-contained HTML page of ``scene`` (a :class:`~mcdm_pin.viewer.scene.Scene`)."""
    umsgpack = optional("umsgpack", "the viewer")

    js = (meshcat_dist() / "main.min.js").read_text(encoding="utf-8")
    blobs = [base64.b64encode(umsgpack.packb(dict(c))).decode("ascii") for c in scene.all_commands()]
    meta = {"t": [float(x) for x in scene.t], "status": [str(s) for s in scene.status],
            "fmax": scene.fmax, "arrow_scale": scene.arrow_scale,
            "colors": ["#%06x" % three.hex_color(c) for c in CABLE_MAP], "info": scene.info,
            "legend": scene.legend, "start": scene.start_time}
    return _HTML.format(title=_html.escape(scene.info[0] if scene.info else "mcdm-pin"),
                        mainjs=js.replace("</script", "<\\/script"),
                        commands=json.dumps(blobs), meta=json.dumps(meta))


def send(scene, vis) -> None:
    """Send the scene to a running ``meshcat.Visualizer``."""
    for c in scene.all_commands():
        vis.window.send(c)


def serve(scene, zmq_url: str | None = None):
    """Start (or connect to) a Meshcat server, send the scene, return the ``meshcat.Visualizer``
    (the live viewer shows the colour bar as a small panel beside the robot)."""
    meshcat = optional("meshcat", "the viewer")

    vis = meshcat.Visualizer(zmq_url=zmq_url)
    commands = list(scene.commands)
    if scene.legend:
        scene.commands[:0] = _legend_commands(scene)
    try:
        send(scene, vis)
    finally:
        scene.commands[:] = commands
    return vis


def _legend_commands(scene) -> list:
    w_px, h_px, png = legend_png(scene.fmax, scene.arrow_scale)
    extent = scene.extent
    w, h = 0.5 * extent, 0.5 * extent * h_px / w_px
    tex = {"uuid": three.uuid(), "wrap": [1001, 1001], "repeat": [1, 1], "image": None}
    img = {"uuid": three.uuid(), "url": "data:image/png;base64," + base64.b64encode(png).decode()}
    tex["image"] = img["uuid"]
    mat = three.material((1, 1, 1), "MeshBasicMaterial", map=tex["uuid"])
    geom = {"uuid": three.uuid(), "type": "PlaneGeometry", "width": w, "height": h}
    obj = three.obj(geom, mat, extra={"textures": [tex], "images": [img]})
    R = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])  # plane x -> display y, y -> z, normal -> x
    T = three.T(R, np.array([0.0, 0.75 * extent, 0.35 * extent]))
    return [Command(type="set_object", object=obj, path="/meshcat/legend"),
            Command(type="set_transform", path="/meshcat/legend", matrix=T.T.flatten().tolist())]


def _font(size: int):
    ImageFont = optional("PIL.ImageFont", "the viewer")

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


def legend_png(fmax: float, arrow_scale: float = 0.0, width: int = 512) -> tuple[int, int, bytes]:
    """The colour bar as a PNG: (width, height, bytes)."""
    Image, ImageDraw = optional("PIL.Image", "the viewer"), optional("PIL.ImageDraw", "the viewer")

    height = width // 4
    img = Image.new("RGB", (width, height), (255, 255, 255))
    d = ImageDraw.Draw(img)
    font = _font(height // 6)
    x0, x1, y0, y1 = width // 16, width - width // 16, height // 3, height // 3 + height // 5
    for x in range(x0, x1):
        rgb = tension_rgb(fmax * (x - x0) / (x1 - x0 - 1), fmax)
        d.line([(x, y0), (x, y1)], fill=tuple(int(255 * c) for c in rgb))
    d.text((x0, 4), "cable tension, N", fill=(0, 0, 0), font=font)
    for k in range(5):
        x = x0 + (x1 - x0 - 1) * k / 4
        d.line([(x, y1), (x, y1 + 6)], fill=(0, 0, 0))
        label = f"{fmax * k / 4:g}"
        d.text((x - 4 * len(label), y1 + 8), label, fill=(0, 0, 0), font=font)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return width, height, buf.getvalue()


def label_png(text: str, height: int = 40) -> tuple[int, int, bytes]:
    """A joint's name as a PNG label (dark text on a white, slightly transparent box):
    (width, height, bytes)."""
    Image, ImageDraw = optional("PIL.Image", "the viewer"), optional("PIL.ImageDraw", "the viewer")

    font = _font(int(height * 0.62))
    probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
    left, top, right, bottom = probe.textbbox((0, 0), text, font=font)
    width = int(right - left + 0.6 * height)
    img = Image.new("RGBA", (width, height), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    d.rounded_rectangle([0, 0, width - 1, height - 1], radius=height // 4, fill=(255, 255, 255, 215),
                        outline=(128, 0, 128, 255), width=2)
    d.text((0.3 * height - left, (height - (bottom - top)) / 2 - top), text, fill=(40, 0, 40, 255), font=font)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return width, height, buf.getvalue()


_HTML = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
  body {{ margin: 0; }}
  #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
  #mcdm-overlay {{ position: absolute; left: 8px; bottom: 8px; padding: 6px 8px;
    background: rgba(255, 255, 255, 0.85); border-radius: 4px; font: 12px sans-serif;
    color: #111; pointer-events: none; width: 300px; }}
  #mcdm-info div {{ white-space: nowrap; overflow: hidden; text-overflow: ellipsis; }}
  #mcdm-bar {{ height: 10px; margin: 3px 0 1px 0; border: 1px solid #555; }}
  #mcdm-ticks {{ display: flex; justify-content: space-between; font-size: 11px; }}
  .mcdm-small {{ font-size: 11px; color: #333; }}
  #mcdm-time {{ font: bold 13px monospace; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="mcdm-overlay" style="display: none">
  <div id="mcdm-info"></div>
  <div id="mcdm-time"></div>
  <div style="margin-top: 4px">cable tension, N (fixed scale)</div>
  <div id="mcdm-bar"></div>
  <div id="mcdm-ticks"></div>
  <div class="mcdm-small" id="mcdm-arrow"></div>
  <div class="mcdm-small">cone: <span style="color: #26bf40">&#9632;</span> force inside rho*,
    <span style="color: #f00">&#9632;</span> outside, grey: no answer</div>
</div>
<script>
{mainjs}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var MCDM_COMMANDS = {commands};
var MCDM = {meta};
(function () {{
  function bytes(s) {{
    var bin = atob(s), out = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }}
  for (var i = 0; i < MCDM_COMMANDS.length; i++) viewer.handle_command_bytearray(bytes(MCDM_COMMANDS[i]));
  var anim = viewer.animator;
  if (MCDM.start !== null && anim.actions.length) {{
    anim.play(); anim.pause(); anim.seek(MCDM.start); anim.display_progress(MCDM.start);
  }}
  if (!MCDM.legend) return;
  var box = document.getElementById("mcdm-overlay");
  box.style.display = "block";
  document.getElementById("mcdm-info").innerHTML = MCDM.info.map(function (s) {{
    return "<div>" + s.replace(/&/g, "&amp;").replace(/</g, "&lt;") + "</div>"; }}).join("");
  document.getElementById("mcdm-bar").style.background =
    "linear-gradient(to right, " + MCDM.colors.join(", ") + ")";
  var ticks = "";
  for (var k = 0; k <= 4; k++) ticks += "<span>" + +(MCDM.fmax * k / 4).toPrecision(4) + "</span>";
  document.getElementById("mcdm-ticks").innerHTML = ticks;
  if (MCDM.arrow_scale > 0) {{
    var n = 0.1 / MCDM.arrow_scale;
    document.getElementById("mcdm-arrow").textContent =
      "interaction force arrows: 0.1 m = " + n.toPrecision(3) + " N";
  }}
  var el = document.getElementById("mcdm-time");
  function tick() {{
    var t = anim.time || 0, T = MCDM.t, k = 0;
    if (T.length) {{
      var lo = 0, hi = T.length - 1;
      while (hi - lo > 1) {{ var mid = (lo + hi) >> 1; if (T[mid] <= t) lo = mid; else hi = mid; }}
      k = (Math.abs(T[hi] - t) < Math.abs(t - T[lo])) ? hi : lo;
      var st = MCDM.status[k];
      el.textContent = "t = " + t.toFixed(3) + " s" + (st === "optimal" ? "" : "  [" + st + "]");
    }}
    requestAnimationFrame(tick);
  }}
  tick();
}})();
</script>
</body>
</html>
"""
