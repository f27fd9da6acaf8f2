/*
 * Pictures with cairo: a square window of a 2D scene, its circles and its contact lines, as
 * a PNG. Written to a temporary name and renamed, like every output of the tool.
 */
#include "cli.h"

#include <cairo.h>
#include <stdlib.h>

/* cairo writes PNGs through a callback: into our atomic output file. */
static cairo_status_t cli_png_write(void *closure, const unsigned char *data, unsigned int length) {
  FILE *f = closure;
  return fwrite(data, 1, length, f) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

int cli_draw_png(const char *path, const cli_elements *e, const nbs_pair *pairs, size_t count,
                 double x0, double y0, double w, int width) {
  if (e->dim != 2 || width < 16 || width > 16384 || !(w > 0)) {
    return cli_fail(CLI_USAGE, "%s: a picture needs a 2D scene and a size of 16 to 16384 pixels", path);
  }
  cairo_surface_t *surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, width);
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(surface);
    return cli_fail(CLI_RESOURCE, "%s: cannot make a %d x %d picture", path, width, width);
  }
  cairo_t *cr = cairo_create(surface);
  const double scale = width / w;
  cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
  cairo_paint(cr);
  cairo_rectangle(cr, 0, 0, width, width);
  cairo_clip(cr);
  /* World to pixels: y grows upwards in the scene, downwards in the picture. */
  cairo_translate(cr, 0, width);
  cairo_scale(cr, scale, -scale);
  cairo_translate(cr, -x0, -y0);

  double rmax = 0;
  for (int64_t k = 0; k < e->n; k++) {
    double r = e->radii ? e->radii[k] : 0.5 * e->diameter;
    rmax = r > rmax ? r : rmax;
  }
  /* Circles: a pale fill and a thin outline. */
  for (int pass = 0; pass < 2; pass++) {
    for (int64_t k = 0; k < e->n; k++) {
      double x = e->coords[2 * k], y = e->coords[2 * k + 1];
      double r = e->radii ? e->radii[k] : 0.5 * e->diameter;
      if (x < x0 - rmax || x > x0 + w + rmax || y < y0 - rmax || y > y0 + w + rmax) continue;
      cairo_new_sub_path(cr);
      cairo_arc(cr, x, y, r, 0, 6.283185307179586);
    }
    if (pass == 0) {
      cairo_set_source_rgb(cr, 0.80, 0.87, 0.96);
      cairo_fill(cr);
    } else {
      cairo_set_source_rgb(cr, 0.15, 0.30, 0.55);
      cairo_set_line_width(cr, 1.0 / scale);
      cairo_stroke(cr);
    }
  }
  /* Contacts: a line between the centres of each touching pair. */
  for (size_t k = 0; k < count; k++) {
    const double *a = e->coords + 2 * (size_t)pairs[k].i;
    const double *b = e->coords + 2 * (size_t)pairs[k].j;
    cairo_move_to(cr, a[0], a[1]);
    cairo_line_to(cr, b[0], b[1]);
  }
  cairo_set_source_rgb(cr, 0.85, 0.10, 0.10);
  cairo_set_line_width(cr, (width >= 512 ? 2.0 : 1.0) / scale);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_stroke(cr);
  cairo_destroy(cr);

  int code;
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    code = cli_fail(CLI_RESOURCE, "%s: drawing failed: %s", path,
                    cairo_status_to_string(cairo_surface_status(surface)));
  } else {
    cli_out o;
    code = cli_out_open(&o, path);
    if (code == CLI_OK) {
      cairo_status_t s = cairo_surface_write_to_png_stream(surface, cli_png_write, o.f);
      if (s != CAIRO_STATUS_SUCCESS) {
        cli_out_abort(&o);
        code = cli_fail(CLI_RESOURCE, "%s: cannot write the PNG: %s", path, cairo_status_to_string(s));
      } else {
        code = cli_out_commit(&o);
      }
    }
  }
  cairo_surface_destroy(surface);
  return code;
}
