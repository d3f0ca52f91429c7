"""What the browser tests and the explorer's benchmark share: Debian's Chromium (or
``$HYBRIDPD_CHROMIUM``), the flags it runs headless with on a closed network, and the script
that finds where Bokeh draws a point of the region map."""
import os

CHROMIUM = os.environ.get("HYBRIDPD_CHROMIUM", "/usr/bin/chromium")
#: without the background-networking flags Chromium keeps trying hosts the network refuses
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
#: Where Bokeh itself draws the point (kp, kv) of the map, in the page's pixels: its own
#: scales and its canvas's box, read together (no assumption about the layout).
MAP_POINT_JS = """([x, y]) => {
  const m = Bokeh.documents.map(d => d.get_model_by_name("region-map")).find(v => v);
  const v = Bokeh.index.find_one(m);
  const r = v.canvas_view.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)];
}"""
