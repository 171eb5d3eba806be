/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_PLOT_H
#define GLINT_CORE_PLOT_H

/*
 * An 8-bit RGB canvas for the plots glint writes as PNG (compare.png's
 * residual plots, hdr's response curve): points, rectangles, lines and
 * text in a 5x7 bitmap font (digits, capitals and the punctuation labels
 * use; other characters are blank), scaled by an integer.  Drawing
 * outside the canvas is clipped.
 *
 * Errors: a negative errno with glint_error_msg().  Threads: a canvas
 * belongs to one thread.  Who frees: glint_canvas_free().
 */

#include <stdint.h>

/* A glyph's advance, in pixels at scale 1. */
#define GLINT_CANVAS_GLYPH_W 6

struct glint_canvas {
	int w, h;
	uint8_t *px; /* w * h * 3, rows top down */
};

/* A white canvas of w x h. */
int glint_canvas_init(struct glint_canvas *cv, int w, int h);
void glint_canvas_free(struct glint_canvas *cv);
void glint_canvas_put(struct glint_canvas *cv, int x, int y,
		      const uint8_t rgb[3]);
/* The rectangle with corners (x0, y0) and (x1, y1), inclusive. */
void glint_canvas_fill(struct glint_canvas *cv, int x0, int y0, int x1, int y1,
		       const uint8_t rgb[3]);
void glint_canvas_line(struct glint_canvas *cv, int x0, int y0, int x1, int y1,
		       const uint8_t rgb[3]);
/* A ring of radius r (pixels) and thickness t about (cx, cy). */
void glint_canvas_ring(struct glint_canvas *cv, double cx, double cy, double r,
		       double t, const uint8_t rgb[3]);
/* Text in near-black, its top-left at (x, y), glyphs scaled by s. */
void glint_canvas_text(struct glint_canvas *cv, int x, int y, int s,
		       const char *str);
/* As an 8-bit PNG (glint_png_write_rgb8). */
int glint_canvas_write_png(const struct glint_canvas *cv, const char *path);

#endif
