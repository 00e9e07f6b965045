/* Histograms of element quality: one panel per view, bars for q in bins of
 * 0.05 over (0, 1] and a separate bar for the tangled elements (q = 0).
 * Counts are drawn on a logarithmic axis (decades 1, 10, 100, ...), so that
 * a handful of poor elements among thousands of good ones still shows; the
 * count is written above each bar.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "render/render_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { BINS = 20, HIST_BAND_ROWS = 64 };

typedef struct hist_panel {
  const hoc_render_mesh *mesh;
  size_t count[BINS + 1]; /* [0]: tangled, [1 + k]: q in bin k */
  int x0, x1;             /* columns of the panel */
} hist_panel;

typedef struct hist_ctx {
  int width, height, n_views;
  hist_panel *panels;
  char (*stats)[96]; /* [n_views] statistics line */
  hoc_render_scale scale;
  int title_scale, label_scale, pad;
  int decades;          /* the axis goes up to 10^decades */
  int plot_y0, plot_y1; /* rows of the plot area (counts axis) */
} hist_ctx;

/* Bin of a non-tangled q: [0.05 k, 0.05 (k + 1)), q = 1 in the last. */
static int bin_of(double q) {
  int k = (int)floor(q * BINS);
  return k >= BINS ? BINS - 1 : k < 0 ? 0 : k;
}

/* Height fraction of a count on the log axis, which runs from 10^-0.5 (so
 * one element is half a decade tall) to a quarter decade above 10^decades
 * (room for the counts over the bars). */
static double log_height(const hist_ctx *h, size_t c) {
  if (c == 0) return 0;
  return (log10((double)c) + 0.5) / (h->decades + 0.75);
}

static void format_count(char *buf, size_t n, double v) {
  if (v < 1e6)
    snprintf(buf, n, "%.0f", v);
  else
    snprintf(buf, n, "1e%d", (int)lround(log10(v)));
}

static void draw_panel(const hist_ctx *h, int view, hoc_canvas *c) {
  const hist_panel *pn = &h->panels[view];
  const int ls = h->label_scale, pad = h->pad;
  const hoc_rgb grid = {225, 225, 225};
  int pw = pn->x1 - pn->x0;
  /* title */
  const char *title = pn->mesh->title ? pn->mesh->title : "";
  int ts = hoc_text_fit(title, h->title_scale, pw - 2 * pad);
  hoc_canvas_text(c, pn->x0 + (pw - hoc_text_width(title, ts)) / 2, pad, title, ts, HOC_RENDER_INK);
  const char *line = h->stats[view];
  int s0 = hoc_text_fit(line, ls, pw - 2 * pad);
  hoc_canvas_text(c, pn->x0 + (pw - hoc_text_width(line, s0)) / 2,
                  pad + HOC_FONT_LINE * h->title_scale, line, s0, HOC_RENDER_INK);
  /* plot rectangle: room for the count labels on the left */
  char label[32];
  format_count(label, sizeof label, pow(10, h->decades));
  int left = pn->x0 + 2 * pad + hoc_text_width(label, ls) + pad;
  int right = pn->x1 - 2 * pad;
  int y0 = h->plot_y0, y1 = h->plot_y1, ph = y1 - y0;
  if (right - left < 4 * (BINS + 2) || ph < 8) return;
  double u = (right - left) / (BINS + 1.5); /* slot width: tangled, gap, 20 bins */
  /* decades: grid line, tick, label */
  for (int d = 0; d <= h->decades; ++d) {
    int y = y1 - (int)lround((d + 0.5) / (h->decades + 0.75) * ph);
    hoc_canvas_rect(c, left, y, right, y + 1, grid, 1);
    hoc_canvas_rect(c, left - pad, y, left, y + 1, HOC_RENDER_INK, 1);
    format_count(label, sizeof label, pow(10, d));
    hoc_canvas_text(c, left - pad - pad / 2 - hoc_text_width(label, ls),
                    y - HOC_FONT_ASCENT * ls / 2, label, ls, HOC_RENDER_INK);
  }
  /* bars with their counts above */
  for (int k = 0; k <= BINS; ++k) {
    size_t n = pn->count[k];
    double xa = k == 0 ? 0 : 1.5 + (k - 1), xb = xa + 1;
    int bx0 = left + (int)lround(xa * u) + 1, bx1 = left + (int)lround(xb * u) - 1;
    if (bx1 <= bx0) bx1 = bx0 + 1;
    hoc_rgb col =
        k == 0 ? HOC_RENDER_TANGLED : hoc_render_quality_colour(&h->scale, (k - 0.5) / BINS);
    int top = y1 - (int)lround(log_height(h, n) * ph);
    if (n > 0) {
      hoc_canvas_rect(c, bx0, top, bx1, y1, col, 1);
      hoc_canvas_frame(c, bx0, top, bx1, y1, 1, HOC_RENDER_INK);
      snprintf(label, sizeof label, "%zu", n);
      int s = hoc_text_fit(label, ls, bx1 - bx0 + 2);
      if (hoc_text_width(label, s) <= bx1 - bx0 + 4 * s)
        hoc_canvas_text(c, (bx0 + bx1 - hoc_text_width(label, s)) / 2, top - HOC_FONT_LINE * s,
                        label, s, HOC_RENDER_INK);
    }
  }
  /* axes */
  hoc_canvas_rect(c, left - 1, y0, left + 1, y1 + 1, HOC_RENDER_INK, 1);
  hoc_canvas_rect(c, left - 1, y1, right, y1 + 2, HOC_RENDER_INK, 1);
  hoc_canvas_text(c, left, y0 - HOC_FONT_LINE * ls - pad / 2, "elements (log scale)", ls,
                  HOC_RENDER_INK);
  /* q ticks every 0.25 under the bins */
  static const char *qlabels[] = {"0", "0.25", "0.5", "0.75", "1"};
  int ly = y1 + 2 + pad;
  for (int i = 0; i <= 4; ++i) {
    int x = left + (int)lround((1.5 + i * BINS / 4.0) * u);
    hoc_canvas_rect(c, x, y1 + 2, x + 1, y1 + 2 + pad / 2, HOC_RENDER_INK, 1);
    hoc_canvas_text(c, x - hoc_text_width(qlabels[i], ls) / 2, ly, qlabels[i], ls, HOC_RENDER_INK);
  }
  int ax = left + (int)lround((1.5 + BINS / 2.0) * u);
  int ly2 = ly + HOC_FONT_LINE * ls;
  hoc_canvas_text(c, ax - hoc_text_width("q", ls) / 2, ly2, "q", ls, HOC_RENDER_INK);
  hoc_canvas_text(c, left, ly2, "tangled", hoc_text_fit("tangled", ls, (int)(1.5 * u) + pad),
                  HOC_RENDER_INK);
  if (pn->x0 > 0) hoc_canvas_rect(c, pn->x0, 0, pn->x0 + 1, h->height, grid, 1);
}

hoc_status hoc_render_histogram_png(const char *path, const hoc_render_mesh *views, int n_views,
                                    const hoc_render_options *options) {
  int width, height;
  HOC_TRY(hoc_render_check_common(path, views, n_views, options, &width, &height));
  for (int k = 0; k < n_views; ++k)
    HOC_CHECK(views[k].q || views[k].n_elems == 0, HOC_ERR_ARGUMENT,
              "histogram: view %d has no qualities", k);
  hoc_status status = HOC_OK;
  hist_ctx h = {.width = width, .height = height, .n_views = n_views};
  unsigned char *buf = NULL;
  hoc_png_out *png = NULL;
  HOC_ALLOC_GOTO(h.panels, (size_t)n_views, done);
  HOC_ALLOC_GOTO(h.stats, (size_t)n_views, done);
  hoc_render_scale_compute(views, n_views, &h.scale);
  size_t cmax = 1;
  int pw = width / n_views;
  for (int k = 0; k < n_views; ++k) {
    hist_panel *pn = &h.panels[k];
    pn->mesh = &views[k];
    hoc_render_stats_line(&views[k], h.stats[k], sizeof h.stats[k]);
    pn->x0 = k * pw;
    pn->x1 = k == n_views - 1 ? width : (k + 1) * pw;
    for (size_t e = 0; e < views[k].n_elems; ++e) {
      double q = hoc_render_q(&views[k], e);
      ++pn->count[q == 0 ? 0 : 1 + bin_of(q)];
    }
    for (int b = 0; b <= BINS; ++b)
      if (pn->count[b] > cmax) cmax = pn->count[b];
  }
  h.decades = (int)ceil(log10((double)cmax) - 1e-12);
  if (h.decades < 1) h.decades = 1;
  int ts = (int)lround(fmin(width / n_views, height) / 400.0);
  h.title_scale = ts < 1 ? 1 : ts > 8 ? 8 : ts;
  h.label_scale = h.title_scale > 1 ? h.title_scale - 1 : 1;
  h.pad = 4 * h.label_scale;
  /* title, statistics, axis name, then the plot */
  h.plot_y0 = 3 * h.pad + HOC_FONT_LINE * (h.title_scale + 2 * h.label_scale);
  h.plot_y1 = height - (3 * h.pad + 2 * HOC_FONT_LINE * h.label_scale);

  int transparent = options ? options->transparent != 0 : 0;
  HOC_ALLOC_GOTO(buf, 4 * (size_t)width * HIST_BAND_ROWS, done);
  HOC_TRY_GOTO(hoc_png_out_open(path, width, height, transparent, &png), done);
  for (int y0 = 0; y0 < height; y0 += HIST_BAND_ROWS) {
    hoc_canvas c = {buf, width, height, y0,
                    height - y0 < HIST_BAND_ROWS ? height - y0 : HIST_BAND_ROWS};
    hoc_canvas_clear(&c, transparent);
    for (int k = 0; k < n_views; ++k)
      draw_panel(&h, k, &c);
    HOC_TRY_GOTO(hoc_png_out_rows(png, &c), done);
  }
  HOC_TRY_GOTO(hoc_png_out_close(&png), done);
done:
  hoc_png_out_abort(&png);
  free(buf);
  free(h.panels);
  free(h.stats);
  return status;
}
