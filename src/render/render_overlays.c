/* What the mesh renderer draws over its panels: titles, statistics lines,
 * rings around tangled elements too small to see, and the colour bar.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "render/raster.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void format_q(char *buf, size_t n, double v) { snprintf(buf, n, "%.2f", v); }

/* Tangled elements too small to see get a ring around them (visible or not:
 * the ring says where to look, or which view to choose). */
hoc_status hoc_render_find_markers(render_ctx *ctx) {
  size_t n = 0;
  for (int pass = 0; pass < 2; ++pass) {
    n = 0;
    for (int k = 0; k < ctx->n_views; ++k) {
      const view_state *vs = &ctx->views[k];
      const hoc_render_mesh *m = vs->mesh;
      if (!m->q) continue;
      for (size_t e = 0; e < m->n_elems && n < MAX_MARKERS; ++e) {
        if (hoc_render_q(m, e) != 0) continue;
        const double *b = vs->box + 4 * e;
        if (ctx->scale * hypot(b[1] - b[0], b[3] - b[2]) >= MARKER_BELOW) continue;
        double x = vs->cx + ctx->scale * (0.5 * (b[0] + b[1]) - ctx->fx);
        double y = vs->cy - ctx->scale * (0.5 * (b[2] + b[3]) - ctx->fy);
        if (x < vs->x0 || x >= vs->x1 || y < ctx->panel_y0 || y >= ctx->height) continue;
        if (pass == 1) {
          ctx->markers[3 * n] = x;
          ctx->markers[3 * n + 1] = y;
          ctx->markers[3 * n + 2] = k;
        }
        ++n;
      }
    }
    if (pass == 0 && n > 0) HOC_ALLOC(ctx->markers, 3 * n);
  }
  ctx->n_markers = n;
  return HOC_OK;
}

/* Anti-aliased ring of radius r and width w (pixels) clipped to columns
 * [x0, x1). */
static void draw_ring(hoc_canvas *c, double cx, double cy, double r, double w, int x0, int x1,
                      hoc_rgb col) {
  int ya = clamp_int(floor(cy - r - w), c->y0, c->y0 + c->rows);
  int yb = clamp_int(ceil(cy + r + w) + 1, c->y0, c->y0 + c->rows);
  int xa = clamp_int(floor(cx - r - w), x0, x1), xb = clamp_int(ceil(cx + r + w) + 1, x0, x1);
  for (int y = ya; y < yb; ++y)
    for (int x = xa; x < xb; ++x) {
      double d = fabs(hypot(x + 0.5 - cx, y + 0.5 - cy) - r);
      hoc_canvas_blend(c, x, y, col, 0.5 * w + 0.5 - d);
    }
}

void hoc_render_draw_overlays(const render_ctx *ctx, hoc_canvas *c) {
  const int ls = ctx->label_scale, pad = ctx->pad;
  const hoc_rgb sep = {215, 215, 215};
  /* one text size for all the titles and one for all the statistics lines,
   * so that the panels read alike */
  int ts_all = ctx->title_scale, ls_all = ls;
  for (int k = 0; k < ctx->n_views; ++k) {
    const view_state *vs = &ctx->views[k];
    int room = vs->x1 - vs->x0 - 2 * pad;
    if (ctx->has_title && vs->mesh->title) {
      int s = hoc_text_fit(vs->mesh->title, ctx->title_scale, room);
      if (s < ts_all) ts_all = s;
    }
    if (ctx->has_stats && ctx->stats[k][0]) {
      int s = hoc_text_fit(ctx->stats[k], ls, room);
      if (s < ls_all) ls_all = s;
    }
  }
  for (int k = 0; k < ctx->n_views; ++k) {
    const view_state *vs = &ctx->views[k];
    int pw = vs->x1 - vs->x0, y = pad;
    if (k > 0) hoc_canvas_rect(c, vs->x0, 0, vs->x0 + 1, ctx->height, sep, 1);
    if (ctx->has_title) {
      const char *title = vs->mesh->title;
      if (title) {
        int s = ts_all;
        int x = vs->x0 + (pw - hoc_text_width(title, s)) / 2;
        hoc_canvas_text(c, x, y + (ctx->title_scale - s) * HOC_FONT_ASCENT, title, s,
                        HOC_RENDER_INK);
      }
      y += HOC_FONT_LINE * ctx->title_scale;
    }
    if (ctx->has_stats && ctx->stats[k][0]) {
      const char *line = ctx->stats[k];
      int s = ls_all;
      int x = vs->x0 + (pw - hoc_text_width(line, s)) / 2;
      hoc_canvas_text(c, x, y, line, s, HOC_RENDER_INK);
    }
  }
  for (size_t i = 0; i < ctx->n_markers; ++i) {
    const double *mk = ctx->markers + 3 * i;
    const view_state *vs = &ctx->views[(int)mk[2]];
    draw_ring(c, mk[0], mk[1], 6 + 3 * ls, 1 + 0.5 * ls, vs->x0, vs->x1, HOC_RENDER_TANGLED);
  }
  if (!ctx->qscale.has_q) return;
  /* colour bar: gradient, frame, ticks with labels, "q" above, tangled below */
  const hoc_render_scale *sc = &ctx->qscale;
  int bx0 = ctx->bar_x0, bx1 = ctx->bar_x1, by0 = ctx->bar_y0, by1 = ctx->bar_y1;
  int bh = by1 - by0;
  if (bh < 4) return;
  for (int y = by0; y < by1; ++y) {
    double t = (by1 - y - 0.5) / bh;
    hoc_canvas_rect(c, bx0, y, bx1, y + 1, hoc_render_colormap(t), 1);
  }
  hoc_canvas_frame(c, bx0 - 1, by0 - 1, bx1 + 1, by1 + 1, 1, HOC_RENDER_INK);
  const char *name = "q";
  hoc_canvas_text(c, bx0 + (bx1 - bx0 - hoc_text_width(name, ls)) / 2,
                  by0 - HOC_FONT_LINE * ls - pad, name, ls, HOC_RENDER_INK);
  double range = sc->hi - sc->lo;
  static const double steps[] = {0.05, 0.1, 0.2, 0.25, 0.5, 1};
  double step = 1;
  for (size_t i = 0; i < sizeof steps / sizeof *steps; ++i) {
    double m = range / steps[i];
    if (m <= 10.5 && bh / m >= 2.5 * HOC_FONT_LINE * ls) {
      step = steps[i];
      break;
    }
  }
  int nt = (int)lround(range / step);
  if (fabs(nt * step - range) > 1e-9) nt = 1, step = range; /* only the ends */
  for (int i = 0; i <= nt; ++i) {
    double v = sc->lo + i * step;
    int y = by1 - (int)lround((v - sc->lo) / range * bh);
    char label[32];
    format_q(label, sizeof label, v);
    hoc_canvas_rect(c, bx1, y - (ls + 1) / 2, bx1 + pad, y - (ls + 1) / 2 + ls, HOC_RENDER_INK, 1);
    hoc_canvas_text(c, bx1 + pad + pad / 2, y - HOC_FONT_ASCENT * ls / 2, label, ls,
                    HOC_RENDER_INK);
  }
  if (sc->tangled) {
    int y = by1 + 3 * pad;
    hoc_canvas_rect(c, bx0, y, bx1, y + bx1 - bx0, HOC_RENDER_TANGLED, 1);
    hoc_canvas_frame(c, bx0 - 1, y - 1, bx1 + 1, y + bx1 - bx0 + 1, 1, HOC_RENDER_INK);
    hoc_canvas_text(c, bx1 + pad + pad / 2, y + (bx1 - bx0 - HOC_FONT_ASCENT * ls) / 2, "tangled",
                    ls, HOC_RENDER_INK);
  }
}
