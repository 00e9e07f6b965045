/* PNG output through libpng's writer, band by band, into an atomic output
 * file. libpng reports errors by longjmp: every function here that calls
 * into libpng sets its own setjmp point first, and the error handler keeps
 * libpng's message for ours. Warnings are dropped (the library never prints).
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "render/render_impl.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct hoc_png_out {
  hoc_outfile out;
  png_structp png;
  png_infop info;
  int width, height, alpha;
  int rows_written;
  unsigned char *row; /* [width][3] when the file is RGB */
  char message[200];  /* libpng's last error */
};

static void png_error_handler(png_structp png, png_const_charp msg) {
  hoc_png_out *p = png_get_error_ptr(png);
  if (p) snprintf(p->message, sizeof p->message, "%s", msg ? msg : "libpng error");
  png_longjmp(png, 1);
}

static void png_warning_handler(png_structp png, png_const_charp msg) {
  (void)png;
  (void)msg;
}

static void png_out_free(hoc_png_out *p) {
  if (p->png) png_destroy_write_struct(&p->png, &p->info);
  free(p->row);
  free(p);
}

void hoc_png_out_abort(hoc_png_out **png) {
  if (!png || !*png) return;
  hoc_outfile_abort(&(*png)->out);
  png_out_free(*png);
  *png = NULL;
}

/* Write the header; separate from open so that the setjmp frame holds no
 * variable the caller changes afterwards. */
static int png_out_header(hoc_png_out *p) {
  if (setjmp(png_jmpbuf(p->png))) return -1;
  png_init_io(p->png, p->out.fp);
  png_set_IHDR(p->png, p->info, (png_uint_32)p->width, (png_uint_32)p->height, 8,
               p->alpha ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(p->png, p->info, PNG_sRGB_INTENT_PERCEPTUAL);
  /* fast deflate: the pictures are large and flat, level 3 is within a few
   * per cent of level 6 in size */
  png_set_compression_level(p->png, 3);
  png_write_info(p->png, p->info);
  return 0;
}

hoc_status hoc_png_out_open(const char *path, int width, int height, int alpha, hoc_png_out **png) {
  *png = NULL;
  hoc_png_out *p = calloc(1, sizeof *p);
  HOC_CHECK(p, HOC_ERR_MEMORY, "out of memory");
  p->width = width;
  p->height = height;
  p->alpha = alpha;
  if (!alpha) {
    p->row = hoc_calloc((size_t)width * 3, 1);
    if (!p->row) {
      png_out_free(p);
      return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    }
  }
  hoc_status status = hoc_outfile_open(&p->out, path);
  if (status != HOC_OK) {
    png_out_free(p);
    return status;
  }
  p->png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, p, png_error_handler, png_warning_handler);
  if (p->png) p->info = png_create_info_struct(p->png);
  if (!p->png || !p->info) {
    hoc_png_out_abort(&p);
    return HOC_ERROR(HOC_ERR_MEMORY, "%s: cannot create the PNG writer", path);
  }
  if (png_out_header(p)) {
    status = HOC_ERROR(HOC_ERR_IO, "%s: %s", path, p->message);
    hoc_png_out_abort(&p);
    return status;
  }
  *png = p;
  return HOC_OK;
}

static int png_out_write(hoc_png_out *p, const hoc_canvas *c) {
  if (setjmp(png_jmpbuf(p->png))) return -1;
  for (int y = 0; y < c->rows; ++y) {
    const unsigned char *src = c->rgba + 4 * (size_t)y * (size_t)c->width; /* [width][4] */
    if (p->alpha) {
      png_write_row(p->png, src);
    } else {
      for (int x = 0; x < c->width; ++x)
        memcpy(p->row + 3 * (size_t)x, src + 4 * (size_t)x, 3);
      png_write_row(p->png, p->row);
    }
  }
  return 0;
}

hoc_status hoc_png_out_rows(hoc_png_out *p, const hoc_canvas *c) {
  HOC_ASSERT(c->width == p->width && c->y0 == p->rows_written && c->y0 + c->rows <= p->height);
  if (png_out_write(p, c)) return HOC_ERROR(HOC_ERR_IO, "%s: %s", p->out.path, p->message);
  p->rows_written += c->rows;
  return HOC_OK;
}

static int png_out_end(hoc_png_out *p) {
  if (setjmp(png_jmpbuf(p->png))) return -1;
  png_write_end(p->png, NULL);
  return 0;
}

hoc_status hoc_png_out_close(hoc_png_out **png) {
  hoc_png_out *p = *png;
  hoc_status status = HOC_OK;
  if (p->rows_written != p->height) {
    status = HOC_ERROR(HOC_ERR_INTERNAL, "%s: %d of %d rows written", p->out.path, p->rows_written,
                       p->height);
  } else if (png_out_end(p)) {
    status = HOC_ERROR(HOC_ERR_IO, "%s: %s", p->out.path, p->message);
  }
  if (status != HOC_OK) {
    hoc_png_out_abort(png);
    return status;
  }
  status = hoc_outfile_commit(&p->out);
  if (status != HOC_OK) hoc_outfile_abort(&p->out);
  png_out_free(p);
  *png = NULL;
  return status;
}
