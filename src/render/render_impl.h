/* Internals shared by the picture and histogram renderers: an RGBA canvas
 * holding a horizontal band of the final image, a bitmap font, the colour
 * map and a PNG writer that takes the image band by band (so memory stays
 * bounded whatever the picture's size).
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_RENDER_IMPL_H
#define HOC_RENDER_IMPL_H

#include "io/io.h"
#include "render/render.h"

#include <stdint.h>

/* Limits checked on the caller's input. */
#define HOC_RENDER_MAX_SIZE 16384 /* pixels, each direction */
#define HOC_RENDER_MIN_SIZE 64
#define HOC_RENDER_MAX_VIEWS 16
#define HOC_RENDER_DEFAULT_WIDTH 1600
#define HOC_RENDER_DEFAULT_HEIGHT 1200

/* Colours, sRGB bytes. */
typedef struct hoc_rgb {
  unsigned char r, g, b;
} hoc_rgb;

#define HOC_RENDER_TANGLED ((hoc_rgb){230, 0, 230}) /* magenta: in no colour of the map */
#define HOC_RENDER_GREY ((hoc_rgb){190, 190, 190})  /* faces when q is not given */
#define HOC_RENDER_INK ((hoc_rgb){30, 30, 30})      /* text, axes */
#define HOC_RENDER_EDGE ((hoc_rgb){20, 20, 20})     /* element edges */

/** Colour of t in [0, 1] (clamped) on the quality map: dark blue-violet (bad)
 *  through blue, teal and green to yellow (good), lightness increasing. */
hoc_rgb hoc_render_colormap(double t);

/** Rows [y0, y0 + rows) of a width x height RGBA image, straight alpha. */
typedef struct hoc_canvas {
  unsigned char *rgba; /* [rows][width][4] */
  int width, height;   /* of the whole image */
  int y0, rows;
} hoc_canvas;

/** Fill the band with the background: opaque white or transparent. */
void hoc_canvas_clear(hoc_canvas *c, int transparent);
/** Composite colour `col` with opacity `alpha` in [0, 1] over pixel (x, y)
 *  ("over" operator); pixels outside the band are ignored. */
void hoc_canvas_blend(hoc_canvas *c, int x, int y, hoc_rgb col, double alpha);
/** Fill the rectangle [x0, x1) x [y0, y1) (clipped) with `col` at `alpha`. */
void hoc_canvas_rect(hoc_canvas *c, int x0, int y0, int x1, int y1, hoc_rgb col, double alpha);
/** Outline of the rectangle [x0, x1) x [y0, y1), `t` pixels thick, inside. */
void hoc_canvas_frame(hoc_canvas *c, int x0, int y0, int x1, int y1, int t, hoc_rgb col);

/* Bitmap font: glyphs of 5 x 9 cells (7 above the baseline, 2 below) on an
 * advance of 6 x 10 cells, each cell `scale` x `scale` pixels. */
enum { HOC_FONT_ADVANCE = 6, HOC_FONT_LINE = 10, HOC_FONT_ASCENT = 7 };

/** Width in pixels of `text` drawn at `scale` (no trailing spacing). */
int hoc_text_width(const char *text, int scale);
/** Draw ASCII text with its top-left corner at (x, y); characters outside
 *  32..126 are drawn as '?'. */
void hoc_canvas_text(hoc_canvas *c, int x, int y, const char *text, int scale, hoc_rgb col);
/** Largest scale in [1, scale] at which `text` is at most `max_width` wide. */
int hoc_text_fit(const char *text, int scale, int max_width);

/** The colour scale shared by the views: q in [lo, hi] maps to the colour
 *  map; lo and hi are the extreme non-tangled q rounded outwards to 0.1. */
typedef struct hoc_render_scale {
  int has_q;      /* some view has q */
  double lo, hi;  /* lo < hi */
  size_t tangled; /* over all views */
} hoc_render_scale;

/** Compute the shared scale of views whose q are already validated. */
void hoc_render_scale_compute(const hoc_render_mesh *views, int n_views, hoc_render_scale *sc);
/** Colour of an element of quality q on the scale (tangled if q == 0). */
hoc_rgb hoc_render_quality_colour(const hoc_render_scale *sc, double q);

/** One line of statistics of a view with q: "N elements, q min A mean B"
 *  and ", T tangled" if any; "" without q. */
void hoc_render_stats_line(const hoc_render_mesh *v, char *buf, size_t size);

/** Check the qualities of a view: finite, in [0, 1] (values up to 1 + 1e-6
 *  are accepted as rounding and read as 1). */
hoc_status hoc_render_check_quality(const hoc_render_mesh *v, int k);
/** Check the picture size and the view count; fill width and height with
 *  the defaults where the options give 0. */
hoc_status hoc_render_check_common(const char *path, const hoc_render_mesh *views, int n_views,
                                   const hoc_render_options *options, int *width, int *height);
/** q of element e clamped to [0, 1]. */
static inline double hoc_render_q(const hoc_render_mesh *v, size_t e) {
  double q = v->q[e];
  return q < 0 ? 0 : q > 1 ? 1 : q;
}

/** A PNG file written row band by row band through the atomic output file. */
typedef struct hoc_png_out hoc_png_out;

/** Open `path` and write the PNG header (8-bit RGB, or RGBA if `alpha`). */
hoc_status hoc_png_out_open(const char *path, int width, int height, int alpha, hoc_png_out **png);
/** Write the canvas's rows (they must follow the rows already written). */
hoc_status hoc_png_out_rows(hoc_png_out *png, const hoc_canvas *c);
/** Finish the file and rename it onto the target; frees `*png` either way. */
hoc_status hoc_png_out_close(hoc_png_out **png);
/** Drop the file (target left as it was) and free; NULL allowed. */
void hoc_png_out_abort(hoc_png_out **png);

#endif
