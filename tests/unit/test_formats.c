/* SPDX-License-Identifier: MIT */
/* Image formats: round trips, the DWAB fallback, and bad input. */
#include "test.h"
#include "exr_windows.h"

#include "core/error.h"
#include "core/exif.h"
#include "core/formats.h"
#include "core/image.h"
#include "core/path.h"
#include "core/atomic_dir.h"

#include <OpenEXR/openexr.h>
#include <dirent.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <png.h>
#include <tiffio.h>
#include <libexif/exif-data.h>

#include <stb_image_write.h> /* Debian's libstb holds the writer */
#include <stdint.h>

/* A test card over 7 decades, with exact zeros. */
static struct glint_image *card(int w, int h)
{
	struct glint_image *img = glint_image_new(w, h);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			float *p = glint_image_px(img, x, y);
			p[0] = (float)(1e-3 * pow(10, 7.0 * x / w));
			p[1] = (float)((x + y) % 5 == 0 ? 0 : 0.01 * (y + 1));
			p[2] = (float)(0.5 + 0.25 * sin(x * 0.3 + y));
		}
	return img;
}

static double max_rel_err(const struct glint_image *a,
			  const struct glint_image *b, double floor)
{
	double worst = 0;
	for (size_t i = 0; i < (size_t)a->width * a->height * 3; i++) {
		double d = fabs(a->data[i] - b->data[i]) /
			   fmax(fabs(a->data[i]), floor);
		worst = fmax(worst, d);
	}
	return worst;
}

static const struct glint_write_opts exr_float = { 0 };
static const struct glint_write_opts exr_half = { .exr_half = 1 };

static void test_exr_float_roundtrip(void)
{
	struct glint_image *a = card(97, 61), *b = NULL;
	const char *p = tmp_path("f.exr");
	CHECK(glint_exr_write(p, a, &exr_float) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b) {
		CHECK(b->width == 97 && b->height == 61, "%dx%d", b->width,
		      b->height);
		CHECK(memcmp(a->data, b->data, 97 * 61 * 3 * 4) == 0,
		      "float EXR round trip is not exact");
	}
	glint_image_free(a);
	glint_image_free(b);
}

/* A data window inside a larger display window (render.exr of a fit
 * cropped to the sphere): read back as the window, placed where it was
 * written, and refused when it does not fit the frame or the format
 * cannot say it. */
static void test_exr_window(void)
{
	struct glint_image *a = card(97, 61), *b = NULL;
	const char *p = tmp_path("win.exr");
	struct glint_write_opts o = { .window_x = 5,
				      .window_y = 17,
				      .frame_width = 200,
				      .frame_height = 100 };
	CHECK(glint_image_write(p, a, &o) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b)
		CHECK(b->width == 97 && b->height == 61 &&
			      !memcmp(a->data, b->data, 97 * 61 * 12),
		      "windowed EXR read back %dx%d", b->width, b->height);
	exr_attr_box2i_t dw, disp;
	CHECK(test_exr_windows(p, &dw, &disp) == 0, "reading %s's header", p);
	CHECK(dw.min.x == 5 && dw.min.y == 17 && dw.max.x == 101 &&
		      dw.max.y == 77,
	      "data window (%d,%d)-(%d,%d)", dw.min.x, dw.min.y, dw.max.x,
	      dw.max.y);
	CHECK(disp.min.x == 0 && disp.min.y == 0 && disp.max.x == 199 &&
		      disp.max.y == 99,
	      "display window (%d,%d)-(%d,%d)", disp.min.x, disp.min.y,
	      disp.max.x, disp.max.y);
	o.window_x = 104; /* 104 + 97 > 200 */
	CHECK(glint_image_write(tmp_path("out.exr"), a, &o) == -EINVAL &&
		      strstr(glint_error_msg(), "inside the 200x100 frame"),
	      "window outside the frame: %s", glint_error_msg());
	o.window_x = 5;
	CHECK(glint_image_write(tmp_path("win.pfm"), a, &o) == -EINVAL &&
		      strstr(glint_error_msg(), "needs an .exr"),
	      "window in a PFM: %s", glint_error_msg());
	glint_error_clear();
	glint_image_free(a);
	glint_image_free(b);
}

static void test_exr_half_roundtrip(void)
{
	struct glint_image *a = card(64, 40), *b = NULL;
	const char *p = tmp_path("h.exr");
	CHECK(glint_exr_write(p, a, &exr_half) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	/* Half has an 11-bit significand: relative error <= 2^-11 for
	 * normal values (>= 6.1e-5); below that the spacing is 6e-8. */
	if (b)
		CHECK(max_rel_err(a, b, 6.1e-5) <= 1.0 / 2048 + 1e-9,
		      "half round trip error %g", max_rel_err(a, b, 6.1e-5));
	glint_image_free(a);
	glint_image_free(b);
}

/* A 64x48 render whose ZIP chunk compresses to exactly its packed size:
 * OpenEXRCore 3.1.5 wrote it corrupt (upstream #2306) before exr.c's
 * compress_or_store() work-around. */
static void test_exr_zip_equal_size(void)
{
	struct glint_image *a = NULL, *b = NULL;
	const char *p = tmp_path("zip.exr");
	CHECK(glint_image_read(GLINT_TEST_DATA "/zip_equal_size.pfm", &a) == 0,
	      "%s", glint_error_msg());
	if (!a)
		return;
	CHECK(glint_exr_write(p, a, &exr_float) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b)
		CHECK(!memcmp(a->data, b->data, 64 * 48 * 12),
		      "ZIP chunk of incompressible data corrupted");
	glint_image_free(a);
	glint_image_free(b);
}

/* Write a tiled, ZIP-compressed EXR with the C API (tiles 16x16). */
static int write_tiled(const char *path, const struct glint_image *img)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	exr_context_t ctx;
	exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
	int part, first = 1;
	const char *names[3] = { "B", "G", "R" };
	const int slot[3] = { 2, 1, 0 };

	if (exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init))
		return -1;
	exr_add_part(ctx, "tiled", EXR_STORAGE_TILED, &part);
	exr_initialize_required_attr_simple(ctx, part, img->width, img->height,
					    EXR_COMPRESSION_ZIP);
	exr_set_tile_descriptor(ctx, part, 16, 16, EXR_TILE_ONE_LEVEL,
				EXR_TILE_ROUND_DOWN);
	for (int c = 0; c < 3; c++)
		exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT,
				EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
	if (exr_write_header(ctx))
		return -1;
	int nx = (img->width + 15) / 16, ny = (img->height + 15) / 16;
	for (int ty = 0; ty < ny; ty++)
		for (int tx = 0; tx < nx; tx++) {
			exr_chunk_info_t ci;
			exr_write_tile_chunk_info(ctx, part, tx, ty, 0, 0, &ci);
			if (first)
				exr_encoding_initialize(ctx, part, &ci, &enc);
			else
				exr_encoding_update(ctx, part, &ci, &enc);
			for (int c = 0; c < enc.channel_count; c++) {
				int s = 0;
				for (int k = 0; k < 3; k++)
					if (!strcmp(enc.channels[c]
							    .channel_name,
						    names[k]))
						s = slot[k];
				enc.channels[c].encode_from_ptr =
					(const uint8_t *)(glint_image_px(
								  img, tx * 16,
								  ty * 16) +
							  s);
				enc.channels[c].user_pixel_stride = 12;
				enc.channels[c].user_line_stride =
					12 * img->width;
				enc.channels[c].user_data_type =
					EXR_PIXEL_FLOAT;
				enc.channels[c].user_bytes_per_element = 4;
			}
			if (first)
				exr_encoding_choose_default_routines(ctx, part,
								     &enc);
			first = 0;
			if (exr_encoding_run(ctx, part, &enc))
				return -1;
		}
	exr_encoding_destroy(ctx, &enc);
	return exr_finish(&ctx) ? -1 : 0;
}

static void test_exr_tiled_read(void)
{
	struct glint_image *a = card(50, 37), *b = NULL;
	const char *p = tmp_path("tiled.exr");
	CHECK(write_tiled(p, a) == 0, "could not write the tiled test file");
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b)
		CHECK(b->width == 50 && b->height == 37 &&
			      !memcmp(a->data, b->data, 50 * 37 * 12),
		      "tiled read differs (%dx%d)", b->width, b->height);
	glint_image_free(a);
	glint_image_free(b);
}

/* A window read from the file is the whole read's crop, to the bit. */
static void check_window(const char *p, const struct glint_image *whole, int x,
			 int y, int w, int h)
{
	struct glint_image_window win = { x, y, w, h };
	struct glint_image *b = NULL, *c = NULL;
	int cropped = 0;

	CHECK(glint_image_read_window(p, whole->width, whole->height, &win, &b,
				      &cropped) == 0 &&
		      cropped,
	      "%s: window %dx%d at (%d, %d): %s", p, w, h, x, y,
	      glint_error_msg());
	c = glint_image_crop(whole, x, y, w, h);
	CHECK(b && c && b->width == w && b->height == h &&
		      !memcmp(b->data, c->data, (size_t)w * h * 12),
	      "%s: window %dx%d at (%d, %d) differs from the crop", p, w, h, x,
	      y);
	glint_image_free(b);
	glint_image_free(c);
}

/* Windows of scanline (ZIP: 16-row chunks), tiled, DWAB and PFM files,
 * at the edges and inside; a window outside is refused; an image of
 * another size than the frame is read whole. */
static void test_read_window(void)
{
	struct glint_image *a = card(50, 70), *w = NULL;
	const char *paths[3] = { tmp_path("w-scan.exr"),
				 tmp_path("w-tiled.exr"), tmp_path("w.pfm") };
	CHECK(glint_exr_write(paths[0], a, &exr_float) == 0, "%s",
	      glint_error_msg());
	CHECK(write_tiled(paths[1], a) == 0, "tiled test file");
	CHECK(glint_image_write(paths[2], a, NULL) == 0, "%s",
	      glint_error_msg());
	for (int k = 0; k < 3; k++) {
		check_window(paths[k], a, 0, 0, 50, 70);
		check_window(paths[k], a, 13, 17, 20, 30);
		check_window(paths[k], a, 49, 69, 1, 1);
		check_window(paths[k], a, 0, 33, 50, 1);
		check_window(paths[k], a, 16, 16, 16, 16);
		struct glint_image_window out = { 40, 60, 11, 5 };
		int cropped = 1;
		CHECK(glint_image_read_window(paths[k], 50, 70, &out, &w,
					      &cropped) == -EINVAL &&
			      !w && strstr(glint_error_msg(), "not inside"),
		      "%s: a window outside: %s", paths[k], glint_error_msg());
		glint_error_clear();
		struct glint_image_window in = { 1, 1, 5, 5 };
		CHECK(glint_image_read_window(paths[k], 64, 70, &in, &w,
					      &cropped) == 0 &&
			      !cropped && w && w->width == 50 &&
			      w->height == 70,
		      "%s: another size's image not read whole", paths[k]);
		glint_image_free(w);
		w = NULL;
	}
	/* Not an EXR: said as the whole read says it. */
	const char *junk = tmp_path("junk.exr");
	FILE *f = fopen(junk, "w");
	if (f) {
		fputs("not an image at all", f);
		fclose(f);
	}
	struct glint_image_window jw = { 0, 0, 4, 4 };
	int jc = 1;
	CHECK(glint_image_read_window(junk, 50, 70, &jw, &w, &jc) < 0 && !w &&
		      !jc &&
		      strstr(glint_error_msg(), "not a readable OpenEXR"),
	      "junk .exr: %s", glint_error_msg());
	glint_error_clear();
	/* DWAB (the C++ library's path): the window of the whole read. */
	struct glint_image *d = NULL;
	const char *dp = GLINT_TEST_DATA "/studio_dwab.exr";
	CHECK(glint_image_read(dp, &d) == 0, "%s", glint_error_msg());
	if (d)
		check_window(dp, d, 300, 100, 200, 150);
	glint_image_free(d);
	glint_image_free(a);
}

/* Blender's studio light map (CC0), DWAB-compressed: C core can't. */
static void test_exr_dwab(void)
{
	struct glint_image *img = NULL;
	const char *p = GLINT_TEST_DATA "/studio_dwab.exr";
	CHECK(glint_image_read(p, &img) == 0, "%s", glint_error_msg());
	if (!img)
		return;
	CHECK(img->width == 1024 && img->height == 512, "size %dx%d",
	      img->width, img->height);
	double sum = 0, mx = 0;
	int bad = 0;
	for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++) {
		bad += !isfinite(img->data[i]);
		sum += img->data[i];
		if (img->data[i] > mx) /* not fmax(): docs/arm64.md */
			mx = img->data[i];
	}
	double mean = sum / (img->width * img->height * 3.0);
	CHECK(bad == 0, "%d non-finite values", bad);
	CHECK(mean > 0.01 && mean < 100 && mx > 2 * mean,
	      "implausible radiance: mean %g max %g", mean, mx);
	glint_image_free(img);
}

/*
 * A copy of the DWAB map whose data window starts at (dx, dy) rather than
 * the origin: the header's dataWindow and each chunk's first row move by
 * the same amounts, so the pixels are the same.  DWAB chunks hold 256 rows.
 */
static int shift_dwab_window(const char *src, const char *dst, int32_t dx,
			     int32_t dy)
{
	FILE *f = fopen(src, "rb");
	static unsigned char b[1 << 22];
	size_t n = f ? fread(b, 1, sizeof(b), f) : 0;
	int32_t box[4] = { 0 };
	size_t pos = 8, dwpos = 0;

	if (f)
		fclose(f);
	if (n < 8 || n == sizeof(b))
		return -1;
	while (pos < n && b[pos]) { /* name, type, size, value */
		size_t name = pos, type = pos + strlen((char *)b + pos) + 1;
		size_t sz = type + strlen((char *)b + type) + 1;
		int32_t len;
		if (sz + 4 > n)
			return -1;
		memcpy(&len, b + sz, 4);
		if (!strcmp((char *)b + name, "dataWindow") && len == 16)
			dwpos = sz + 4;
		pos = sz + 4 + (size_t)len;
	}
	if (!dwpos || ++pos > n)
		return -1;
	memcpy(box, b + dwpos, 16);
	int chunks = (box[3] - box[1] + 1 + 255) / 256;
	box[0] += dx, box[2] += dx, box[1] += dy, box[3] += dy;
	memcpy(b + dwpos, box, 16);
	for (int c = 0; c < chunks; c++) {
		uint64_t off;
		int32_t y;
		memcpy(&off, b + pos + 8 * (size_t)c, 8);
		if (off + 4 > n)
			return -1;
		memcpy(&y, b + off, 4);
		y += dy;
		memcpy(b + off, &y, 4);
	}
	f = fopen(dst, "wb");
	if (!f)
		return -1;
	int ok = fwrite(b, 1, n, f) == n;
	return fclose(f) == 0 && ok ? 0 : -1;
}

/* The C++ reader's frame buffer is addressed from the data window's
 * origin; one far from (0, 0) (here min.y × width > INT_MAX) reads the
 * same pixels as the map at the origin. */
static void test_exr_dwab_offset_window(void)
{
	const char *p = GLINT_TEST_DATA "/studio_dwab.exr";
	const char *q = tmp_path("dwab-offset.exr");
	struct glint_image *a = NULL, *b = NULL;

	CHECK(shift_dwab_window(p, q, -7, 1000000000) == 0,
	      "could not write the shifted copy");
	CHECK(glint_image_read(p, &a) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(q, &b) == 0, "%s", glint_error_msg());
	if (a && b) {
		size_t n = (size_t)a->width * a->height * 3, diff = 0;
		CHECK(b->width == a->width && b->height == a->height,
		      "size %dx%d", b->width, b->height);
		for (size_t i = 0;
		     i < n && b->width == a->width && b->height == a->height;
		     i++)
			diff += a->data[i] != b->data[i];
		CHECK(diff == 0, "%zu values differ", diff);
	}
	glint_image_free(a);
	glint_image_free(b);
}

static void test_rgbe_roundtrip(void)
{
	int widths[2] = { 123, 5 }; /* RLE scanlines, and flat (< 8) */
	for (int k = 0; k < 2; k++) {
		struct glint_image *a = card(widths[k], 17), *b = NULL;
		const char *p = tmp_path("r.hdr");
		CHECK(glint_rgbe_write(p, a) == 0, "%s", glint_error_msg());
		CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
		if (!b)
			continue;
		/* RGBE: 8-bit mantissa shared by the pixel's largest
		 * channel; error <= 1/256 of that channel (+ half a step). */
		double worst = 0;
		for (int i = 0; i < widths[k] * 17; i++) {
			const float *pa = a->data + 3 * i,
				    *pb = b->data + 3 * i;
			double m = fmax(pa[0], fmax(pa[1], pa[2]));
			for (int c = 0; c < 3; c++)
				worst = fmax(worst, fabs(pa[c] - pb[c]) / m);
		}
		CHECK(worst <= 1.0 / 256, "width %d: RGBE error %g of max",
		      widths[k], worst);
		glint_image_free(a);
		glint_image_free(b);
	}
}

static void test_pfm_roundtrip(void)
{
	struct glint_image *a = card(31, 7), *b = NULL;
	const char *p = tmp_path("x.pfm");
	CHECK(glint_pfm_write(p, a) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b)
		CHECK(!memcmp(a->data, b->data, 31 * 7 * 12),
		      "PFM round trip is not exact");
	glint_image_free(b);

	/* Big-endian grey map written by hand: rows bottom to top. */
	FILE *fp = fopen(tmp_path("be.pfm"), "wb");
	fprintf(fp, "Pf\n2 2\n1.0\n");
	float v[4] = { 1, 2, 3, 4 };
	for (int i = 0; i < 4; i++) {
		uint8_t *q = (uint8_t *)&v[i];
		fputc(q[3], fp);
		fputc(q[2], fp);
		fputc(q[1], fp);
		fputc(q[0], fp);
	}
	fclose(fp);
	CHECK(glint_image_read(tmp_path("be.pfm"), &b) == 0, "%s",
	      glint_error_msg());
	if (b) {
		CHECK(glint_image_px(b, 0, 1)[0] == 1 &&
			      glint_image_px(b, 1, 0)[2] == 4,
		      "big-endian grey PFM read wrong: %g %g",
		      glint_image_px(b, 0, 1)[0], glint_image_px(b, 1, 0)[2]);
	}
	glint_image_free(a);
	glint_image_free(b);
}

/* A TIFF written with libtiff directly: w x h, spp samples of `bits`. */
static void write_tiff(const char *path, int w, int h, int spp, int bits,
		       const void *data)
{
	TIFF *t = TIFFOpen(path, "w");
	TIFFSetField(t, TIFFTAG_IMAGEWIDTH, w);
	TIFFSetField(t, TIFFTAG_IMAGELENGTH, h);
	TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits);
	TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, spp);
	TIFFSetField(t, TIFFTAG_PHOTOMETRIC,
		     spp == 1 ? PHOTOMETRIC_MINISBLACK : PHOTOMETRIC_RGB);
	TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
	TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_LZW);
	size_t row = (size_t)w * spp * bits / 8;
	for (int y = 0; y < h; y++)
		TIFFWriteScanline(t, (char *)data + row * y, (uint32_t)y, 0);
	TIFFClose(t);
}

static void test_tiff(void)
{
	/* Float out and in: exact. */
	struct glint_image *a = card(37, 11), *b = NULL;
	const char *p = tmp_path("x.tif");
	CHECK(glint_image_write(p, a, NULL) == 0, "%s", glint_error_msg());
	CHECK(glint_image_read(p, &b) == 0, "%s", glint_error_msg());
	if (b)
		CHECK(b->width == 37 && b->height == 11 &&
			      !memcmp(a->data, b->data, 37 * 11 * 12),
		      "float TIFF round trip is not exact");
	glint_image_free(b);
	b = NULL;

	/* 16-bit grey (LZW): linear, value / 65535, grey to all three. */
	uint16_t g16[6] = { 0, 1, 65535, 32768, 100, 7 };
	write_tiff(tmp_path("g16.tiff"), 3, 2, 1, 16, g16);
	CHECK(glint_image_read(tmp_path("g16.tiff"), &b) == 0, "%s",
	      glint_error_msg());
	if (b) {
		CHECK(glint_image_px(b, 2, 0)[1] == 1.0f &&
			      fabs(glint_image_px(b, 0, 1)[2] -
				   32768 / 65535.0) < 1e-7,
		      "16-bit TIFF read as %g %g", glint_image_px(b, 2, 0)[1],
		      glint_image_px(b, 0, 1)[2]);
	}
	glint_image_free(b);
	b = NULL;

	/* 8-bit RGB: code values for the LDR readers, refused as radiance. */
	uint8_t rgb8[2 * 2 * 3] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 250, 251, 252 };
	write_tiff(tmp_path("c8.tif"), 2, 2, 3, 8, rgb8);
	CHECK(glint_image_read(tmp_path("c8.tif"), &b) < 0 && !b,
	      "an 8-bit TIFF was read as radiance");
	CHECK_MSG(glint_error_msg(), "c8.tif: an 8-bit TIFF");
	uint8_t *px = NULL;
	int w = 0, h = 0;
	CHECK(glint_ldr_read(tmp_path("c8.tif"), &w, &h, &px) == 0 && w == 2 &&
		      h == 2 && px && !memcmp(px, rgb8, sizeof(rgb8)),
	      "8-bit TIFF code values: %s", glint_error_msg());
	free(px);

	/* Cut short: refused, naming the file. */
	FILE *in = fopen(p, "rb"), *out = fopen(tmp_path("cut.tif"), "wb");
	char buf[256];
	size_t n = fread(buf, 1, sizeof(buf), in);
	fwrite(buf, 1, n, out);
	fclose(in);
	fclose(out);
	CHECK(glint_image_read(tmp_path("cut.tif"), &b) < 0 && !b,
	      "a cut TIFF was read");
	CHECK_MSG(glint_error_msg(), "cut.tif");
	glint_image_free(a);
}

/* A JPEG with an EXIF ExposureTime of num/den: stb writes the JPEG,
 * libexif makes the EXIF block, which goes in as APP1 after SOI. */
static int write_jpeg_exif(const char *path, unsigned num, unsigned den)
{
	uint8_t px[8 * 8 * 3];
	for (int i = 0; i < (int)sizeof(px); i++)
		px[i] = (uint8_t)(i * 7);
	const char *plain = tmp_path("plain.jpg");
	if (!stbi_write_jpg(plain, 8, 8, 3, px, 90))
		return -1;
	FILE *fp = fopen(plain, "rb");
	uint8_t jpg[65536];
	size_t n = fread(jpg, 1, sizeof(jpg), fp);
	fclose(fp);

	ExifData *ed = exif_data_new();
	exif_data_set_byte_order(ed, EXIF_BYTE_ORDER_INTEL);
	ExifEntry *e = exif_entry_new();
	exif_content_add_entry(ed->ifd[EXIF_IFD_EXIF], e);
	exif_entry_initialize(e, EXIF_TAG_EXPOSURE_TIME);
	ExifRational r = { num, den };
	exif_set_rational(e->data, EXIF_BYTE_ORDER_INTEL, r);
	exif_entry_unref(e);
	unsigned char *blob = NULL;
	unsigned len = 0;
	exif_data_save_data(ed, &blob, &len);
	exif_data_unref(ed);

	fp = fopen(path, "wb");
	uint8_t app1[4] = { 0xff, 0xe1, (uint8_t)((len + 2) >> 8),
			    (uint8_t)((len + 2) & 0xff) };
	fwrite(jpg, 1, 2, fp); /* SOI */
	fwrite(app1, 1, 4, fp);
	fwrite(blob, 1, len, fp);
	fwrite(jpg + 2, 1, n - 2, fp);
	fclose(fp);
	free(blob);
	return 0;
}

/* JPEG through libjpeg-turbo: a smooth card written by stb's encoder reads
 * back within a few code values, under any name; a JPEG cut short, one
 * with a damaged Huffman table and one with fill bytes before its SOI are
 * errors naming the file.  A GIF is refused by name; a PNG named .bmp is
 * read by libpng. */
static void test_jpeg_read(void)
{
	enum { W = 64, H = 48 };
	static uint8_t px[W * H * 3];
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			uint8_t *p = px + 3 * (y * W + x);
			p[0] = (uint8_t)(40 + 2 * x);
			p[1] = (uint8_t)(30 + 3 * y);
			p[2] = 128;
		}
	const char *names[2] = { tmp_path("card.jpg"), tmp_path("card.tga") };
	for (int k = 0; k < 2; k++) {
		uint8_t *rgb = NULL;
		int w = 0, h = 0, worst = 0;
		CHECK(stbi_write_jpg(names[k], W, H, 3, px, 100), "writing");
		CHECK(glint_ldr_read(names[k], &w, &h, &rgb) == 0 && rgb &&
			      w == W && h == H,
		      "%s: %s", names[k], glint_error_msg());
		for (int i = 0; rgb && i < W * H * 3; i++)
			if (abs(rgb[i] - px[i]) > worst)
				worst = abs(rgb[i] - px[i]);
		CHECK(worst <= 4, "%s: off by %d code values", names[k], worst);
		free(rgb);
	}
	/* cut after 60 % of its bytes: libjpeg would pad it with grey */
	const char *cut = tmp_path("cut.jpg");
	FILE *in = fopen(names[0], "rb"), *out = fopen(cut, "wb");
	static uint8_t buf[65536];
	size_t n = in ? fread(buf, 1, sizeof(buf), in) : 0;
	if (out)
		fwrite(buf, 1, n * 6 / 10, out);
	if (in)
		fclose(in);
	if (out)
		fclose(out);
	uint8_t *rgb = NULL;
	int w, h;
	CHECK(glint_ldr_read(cut, &w, &h, &rgb) == -EIO && !rgb,
	      "a cut JPEG was read");
	CHECK_MSG(glint_error_msg(), "cut.jpg: not a readable JPEG");
	glint_error_clear();
	const char *bad = GLINT_TEST_DATA "/../fuzz/regressions/exif/"
					  "jpeg-huffman-table-stb-asserts";
	CHECK(glint_ldr_read(bad, &w, &h, &rgb) == -EIO && !rgb,
	      "a damaged Huffman table was read");
	CHECK_MSG(glint_error_msg(), "not a readable JPEG");
	glint_error_clear();
	/* 0xff fill bytes before the SOI: stb would take it for a JPEG and
	 * assert on its damaged table; libjpeg-turbo refuses it */
	const char *fill =
		GLINT_TEST_DATA "/../fuzz/regressions/stb/"
				"jpeg-fill-bytes-before-soi-stb-asserts";
	CHECK(glint_ldr_read(fill, &w, &h, &rgb) == -EIO && !rgb,
	      "a JPEG with fill bytes before its SOI was read");
	CHECK_MSG(glint_error_msg(), "not a readable JPEG");
	glint_error_clear();
	/* a format stb decodes but glint does not read: named, not decoded */
	const char *gif = tmp_path("gif-named.tga");
	FILE *g = fopen(gif, "wb");
	if (g) {
		fputs("GIF89a", g);
		fclose(g);
	}
	CHECK(glint_ldr_read(gif, &w, &h, &rgb) == -EIO && !rgb,
	      "a GIF was read");
	CHECK_MSG(glint_error_msg(), "a GIF image");
	glint_error_clear();
	/* a PNG by its signature, whatever its name: libpng, not stb */
	const char *png = tmp_path("png-named.bmp");
	CHECK(glint_png_write_rgb8(png, W, H, px) == 0, "writing %s: %s", png,
	      glint_error_msg());
	CHECK(glint_ldr_read(png, &w, &h, &rgb) == 0 && rgb && w == W &&
		      h == H && !memcmp(rgb, px, sizeof(px)),
	      "a PNG named .bmp: %s", glint_error_msg());
	free(rgb);
	rgb = NULL;
}

static void test_exif(void)
{
	double t = 0;
	const char *p = tmp_path("e.jpg");
	CHECK(write_jpeg_exif(p, 1, 250) == 0, "writing %s", p);
	CHECK(glint_exif_exposure_time(p, &t) == 0 && t == 1.0 / 250,
	      "JPEG EXIF ExposureTime 1/250: %g (%s)", t, glint_error_msg());
	CHECK(glint_exif_exposure_time(tmp_path("plain.jpg"), &t) < 0,
	      "a JPEG without EXIF gave a time");
	CHECK_MSG(glint_error_msg(), "plain.jpg: no EXIF data");
	CHECK(write_jpeg_exif(p, 0, 1) == 0, "writing %s", p);
	CHECK(glint_exif_exposure_time(p, &t) < 0, "a zero time was taken");
	CHECK_MSG(glint_error_msg(), "ExposureTime 0 s");

	/* TIFF: an EXIF directory written with libtiff. */
	const char *q = tmp_path("e.tif");
	TIFF *tif = TIFFOpen(q, "w");
	uint8_t row[4 * 3] = { 0 };
	TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, 4);
	TIFFSetField(tif, TIFFTAG_IMAGELENGTH, 1);
	TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 8);
	TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 3);
	TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB);
	TIFFSetField(tif, TIFFTAG_EXIFIFD, (uint64_t)0);
	TIFFWriteScanline(tif, row, 0, 0);
	TIFFWriteDirectory(tif);
	uint64_t off = 0;
	TIFFCreateEXIFDirectory(tif);
	TIFFSetField(tif, EXIFTAG_EXPOSURETIME, 0.5);
	TIFFWriteCustomDirectory(tif, &off);
	TIFFSetDirectory(tif, 0);
	TIFFSetField(tif, TIFFTAG_EXIFIFD, off);
	TIFFClose(tif);
	CHECK(glint_exif_exposure_time(q, &t) == 0 && t == 0.5,
	      "TIFF EXIF ExposureTime 0.5: %g (%s)", t, glint_error_msg());
	CHECK(glint_exif_exposure_time(tmp_path("c8.tif"), &t) < 0,
	      "a TIFF without EXIF gave a time");
	CHECK_MSG(glint_error_msg(), "c8.tif: no EXIF directory");
}

static void test_png_tonemap(void)
{
	struct glint_image *a = glint_image_new(4, 2);
	png_image pi;
	uint8_t buf[4 * 2 * 3];

	for (int i = 0; i < 8; i++) {
		float *p = a->data + 3 * i;
		p[0] = p[1] = p[2] = (float)(i * 0.125);
	}
	CHECK(glint_png_write(tmp_path("t.png"), a, 1.0) == 0, "%s",
	      glint_error_msg());
	memset(&pi, 0, sizeof(pi));
	pi.version = PNG_IMAGE_VERSION;
	CHECK(png_image_begin_read_from_file(&pi, tmp_path("t.png")),
	      "libpng cannot read our PNG");
	pi.format = PNG_FORMAT_RGB;
	CHECK(png_image_finish_read(&pi, NULL, buf, 0, NULL),
	      "libpng cannot decode our PNG");
	/* Pixel 2: 0.25 * 2^1 = 0.5 linear -> sRGB 0.7354 -> 188. */
	CHECK(buf[2 * 3] == 188, "0.5 linear gave %d, expected 188",
	      buf[2 * 3]);
	/* Pixel 5: 0.625 * 2 clips to 255. */
	CHECK(buf[5 * 3] == 255, "clipped value gave %d", buf[5 * 3]);
	CHECK(buf[0] == 0, "black gave %d", buf[0]);
	glint_image_free(a);
}

static long file_size(const char *p)
{
	FILE *fp = fopen(p, "rb");
	fseek(fp, 0, SEEK_END);
	long n = ftell(fp);
	fclose(fp);
	return n;
}

static void copy_prefix(const char *src, const char *dst, long n)
{
	FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
	for (long i = 0; i < n; i++) {
		int c = fgetc(in);
		if (c == EOF)
			break;
		fputc(c, out);
	}
	fclose(in);
	fclose(out);
}

static void scribble(const char *p, long at, int n)
{
	FILE *fp = fopen(p, "r+b");
	fseek(fp, at, SEEK_SET);
	for (int i = 0; i < n; i++)
		fputc(0xA5 ^ (i * 37), fp);
	fclose(fp);
}

static void expect_read_error(const char *p, const char *frag)
{
	struct glint_image *img = NULL;
	int ret = glint_image_read(p, &img);
	CHECK(ret < 0 && img == NULL, "reading %s succeeded", p);
	CHECK_MSG(glint_error_msg(), p);
	if (frag)
		CHECK_MSG(glint_error_msg(), frag);
	glint_image_free(img);
}

static void test_bad_exr(void)
{
	struct glint_image *a = card(128, 128);
	const char *good = tmp_path("good.exr");
	glint_exr_write(good, a, &exr_float);
	long n = file_size(good);

	copy_prefix(good, tmp_path("trunc.exr"), n * 6 / 10);
	expect_read_error(tmp_path("trunc.exr"), NULL);
	copy_prefix(good, tmp_path("hdr.exr"), 40);
	expect_read_error(tmp_path("hdr.exr"), NULL);
	copy_prefix(good, tmp_path("corrupt.exr"), n);
	scribble(tmp_path("corrupt.exr"), n / 2, 200);
	expect_read_error(tmp_path("corrupt.exr"), NULL);
	FILE *fp = fopen(tmp_path("text.exr"), "w");
	fputs("this is not an EXR file at all\n", fp);
	fclose(fp);
	expect_read_error(tmp_path("text.exr"), "not a readable OpenEXR");
	expect_read_error(tmp_path("missing.exr"), "cannot open");
	glint_image_free(a);
}

static void test_bad_rgbe(void)
{
	struct glint_image *a = card(100, 20);
	const char *good = tmp_path("good.hdr");
	glint_rgbe_write(good, a);
	long n = file_size(good);

	copy_prefix(good, tmp_path("trunc.hdr"), n - 300);
	expect_read_error(tmp_path("trunc.hdr"), "truncated in pixel row");
	copy_prefix(good, tmp_path("nores.hdr"), 30);
	expect_read_error(tmp_path("nores.hdr"), NULL);
	/* A run length of 0 right after the first scanline header. */
	copy_prefix(good, tmp_path("rle.hdr"), n);
	long hdr = n;
	{
		FILE *fp = fopen(good, "rb");
		char line[256];
		while (fgets(line, sizeof(line), fp))
			if (line[0] == '-') {
				hdr = ftell(fp);
				break;
			}
		fclose(fp);
	}
	FILE *fp = fopen(tmp_path("rle.hdr"), "r+b");
	fseek(fp, hdr + 4, SEEK_SET);
	fputc(0, fp);
	fclose(fp);
	expect_read_error(tmp_path("rle.hdr"), "corrupt run length");
	fp = fopen(tmp_path("xyz.hdr"), "w");
	fputs("#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 2\n", fp);
	fclose(fp);
	expect_read_error(tmp_path("xyz.hdr"), "FORMAT=32-bit_rle_rgbe");
	glint_image_free(a);
}

static void test_bad_pfm(void)
{
	struct glint_image *a = card(20, 20);
	glint_pfm_write(tmp_path("g.pfm"), a);
	copy_prefix(tmp_path("g.pfm"), tmp_path("t.pfm"),
		    file_size(tmp_path("g.pfm")) - 10);
	expect_read_error(tmp_path("t.pfm"), "needs at least 4800 bytes");
	FILE *fp = fopen(tmp_path("h.pfm"), "w");
	fputs("P6\n2 2\n255\n", fp);
	fclose(fp);
	expect_read_error(tmp_path("h.pfm"), "bad PFM header");
	glint_image_free(a);
}

static void write_bytes(const char *p, const void *data, size_t n)
{
	FILE *fp = fopen(p, "wb");
	fwrite(data, 1, n, fp);
	fclose(fp);
}

static uint32_t crc32_of(const uint8_t *b, size_t n)
{
	uint32_t c = 0xffffffffu;
	for (size_t i = 0; i < n; i++) {
		c ^= b[i];
		for (int k = 0; k < 8; k++)
			c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1)));
	}
	return ~c;
}

static void put_be32(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)(v >> 24);
	p[1] = (uint8_t)(v >> 16);
	p[2] = (uint8_t)(v >> 8);
	p[3] = (uint8_t)v;
}

/* Overwrite a small EXR's dataWindow (box2i after its name and type). */
static void exr_set_window(const char *p, int w, int h)
{
	FILE *fp = fopen(p, "r+b");
	char buf[4096];
	size_t n = fread(buf, 1, sizeof(buf), fp);
	const char key[] = "dataWindow\0box2i\0";
	for (size_t i = 0; i + sizeof(key) + 4 + 16 < n; i++)
		if (!memcmp(buf + i, key, sizeof(key) - 1)) {
			int32_t box[4] = { 0, 0, w - 1, h - 1 };
			fseek(fp, (long)(i + sizeof(key) - 1 + 4), SEEK_SET);
			fwrite(box, 4, 4, fp);
			break;
		}
	fclose(fp);
}

/*
 * Headers that promise more than the file holds are refused before
 * anything is allocated: each of these asks for up to 2.8 GB.  The peak memory
 * of the whole test stays small.
 */
static void test_header_bombs(void)
{
	/* A 20-byte TGA: 18-byte header of 30000 x 25000 RGB, 2 bytes. */
	uint8_t tga[20] = { 0, 0, 2 };
	tga[12] = 30000 & 0xff, tga[13] = 30000 >> 8;
	tga[14] = 25000 & 0xff, tga[15] = 25000 >> 8;
	tga[16] = 24;
	write_bytes(tmp_path("bomb.tga"), tga, sizeof(tga));
	expect_read_error(tmp_path("bomb.tga"), "header says 30000x25000");
	tga[12] = 8000 & 0xff, tga[13] = 8000 >> 8;
	tga[14] = 6000 & 0xff, tga[15] = 6000 >> 8;
	write_bytes(tmp_path("bomb2.tga"), tga, sizeof(tga));
	expect_read_error(tmp_path("bomb2.tga"), "the file holds 20");

	const char rgbe[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
			    "-Y 8000 +X 8000\n\2\2\x1f\x40";
	write_bytes(tmp_path("bomb.hdr"), rgbe, sizeof(rgbe) - 1);
	expect_read_error(tmp_path("bomb.hdr"),
			  "resolution line says 8000x8000");
	const char rgbe_big[] = "#?RADIANCE\n\n-Y 60000 +X 60000\n";
	write_bytes(tmp_path("huge.hdr"), rgbe_big, sizeof(rgbe_big) - 1);
	expect_read_error(tmp_path("huge.hdr"), "GLINT_MAX_PIXELS");

	const char pfm[] = "PF\n8000 8000\n-1.0\n0123456789abcdef";
	write_bytes(tmp_path("bomb.pfm"), pfm, sizeof(pfm) - 1);
	expect_read_error(tmp_path("bomb.pfm"), "PFM header says 8000x8000");

	struct glint_image *a = card(16, 16);
	CHECK(glint_exr_write(tmp_path("bomb.exr"), a, &exr_half) == 0, "%s",
	      glint_error_msg());
	exr_set_window(tmp_path("bomb.exr"), 8000, 8000);
	expect_read_error(tmp_path("bomb.exr"), "dataWindow says 8000x8000");

	/* A PNG whose IHDR (CRC fixed) says 20000 x 20000. */
	CHECK(glint_png_write(tmp_path("bomb.png"), a, 0) == 0, "%s",
	      glint_error_msg());
	FILE *fp = fopen(tmp_path("bomb.png"), "r+b");
	uint8_t ihdr[17];
	fseek(fp, 12, SEEK_SET);
	CHECK(fread(ihdr, 1, 17, fp) == 17 && !memcmp(ihdr, "IHDR", 4),
	      "no IHDR");
	put_be32(ihdr + 4, 20000);
	put_be32(ihdr + 8, 20000);
	uint8_t crc[4];
	put_be32(crc, crc32_of(ihdr, 17));
	fseek(fp, 12, SEEK_SET);
	fwrite(ihdr, 1, 17, fp);
	fwrite(crc, 1, 4, fp);
	fclose(fp);
	expect_read_error(tmp_path("bomb.png"), "IHDR says 20000x20000");

	/* A chunk whose length promises 2 GB in a small file (found by
	 * fuzz_png: libpng allocated it before reading). */
	CHECK(glint_png_write(tmp_path("ok.png"), a, 0) == 0, "%s",
	      glint_error_msg());
	uint8_t head[33], itxt[8] = { 0x7a, 0, 0, 0, 'i', 'T', 'X', 't' };
	fp = fopen(tmp_path("ok.png"), "rb");
	CHECK(fread(head, 1, 33, fp) == 33, "short PNG");
	fclose(fp);
	fp = fopen(tmp_path("chunk.png"), "wb");
	fwrite(head, 1, 33, fp);
	fwrite(itxt, 1, 8, fp);
	fwrite("0123456789", 1, 10, fp);
	fclose(fp);
	expect_read_error(tmp_path("chunk.png"),
			  "chunk 'iTXt' at byte 33 says 2046820352 bytes");

	/* An EXR header attribute of 1.7 GB in a 704-byte file, which the
	 * C++ fallback allocated (found by fuzz_exr). */
	copy_prefix(GLINT_TEST_DATA "/../fuzz/regressions/exr/"
				    "type-string-1.7gb-in-704-bytes",
		    tmp_path("attr.exr"), 704);
	expect_read_error(tmp_path("attr.exr"),
			  "header attribute 'type' says 1701273965 bytes");
	/* A channel list shorter than its stated size: the C++ library
	 * reads by the list, so on out of step with the sizes, into an
	 * opaque attribute of 1.6 GB (found by fuzz_exr). */
	copy_prefix(GLINT_TEST_DATA
		    "/../fuzz/regressions/exr/"
		    "chlist-short-then-opaque-1.6gb-in-756-bytes",
		    tmp_path("chlist.exr"), 756);
	expect_read_error(tmp_path("chlist.exr"),
			  "header attribute 'chennals' of type chlist says "
			  "55 bytes");
	/* A preview of 2^32 - 1 squared pixels: 4wh overflows 64 bits if
	 * the check multiplies it out first (a fuzz_exr input). */
	copy_prefix(GLINT_TEST_DATA "/../fuzz/regressions/exr/"
				    "preview-4wh-overflows-64-bits",
		    tmp_path("preview.exr"), 832);
	expect_read_error(tmp_path("preview.exr"),
			  "header attribute 'thumb' of type preview says 8 "
			  "bytes at byte 26, but its value is not a preview");

	/* The limit is configurable; a good file over it is refused. */
	glint_pfm_write(tmp_path("ok.pfm"), a);
	setenv("GLINT_MAX_PIXELS", "100", 1);
	expect_read_error(tmp_path("ok.pfm"), "above the limit of 100");
	unsetenv("GLINT_MAX_PIXELS");
	struct glint_image *b = NULL;
	CHECK(glint_image_read(tmp_path("ok.pfm"), &b) == 0, "%s",
	      glint_error_msg());
	glint_image_free(b);
	glint_image_free(a);

	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	CHECK(ru.ru_maxrss < 400 * 1024, "peak memory %ld KiB", ru.ru_maxrss);
}

static void test_nonfinite(void)
{
	struct glint_image *a = card(8, 8);
	glint_image_px(a, 3, 2)[1] = NAN;
	glint_image_px(a, 5, 5)[0] = INFINITY;
	CHECK(glint_image_check_finite(a, "probe.exr", 0) == -EINVAL,
	      "NaN not caught");
	CHECK_MSG(glint_error_msg(), "probe.exr: pixel (3, 2) channel G");
	CHECK_MSG(glint_error_msg(), "2 bad values");
	glint_image_free(a);
}

static void test_write_errors(void)
{
	struct glint_image *a = card(8, 8);
	CHECK(glint_image_write("/nonexistent-dir/x.exr", a, NULL) < 0,
	      "write into a missing folder succeeded");
	CHECK_MSG(glint_error_msg(), "/nonexistent-dir/x.exr");
	CHECK(glint_image_write(tmp_path("x.webp"), a, NULL) < 0,
	      "unknown extension accepted");
	CHECK_MSG(glint_error_msg(), "unknown image extension");
	/* No temporary files are left behind. */
	DIR *d = opendir(test_tmpdir());
	struct dirent *e;
	int leftovers = 0;
	while ((e = readdir(d)))
		leftovers += strstr(e->d_name, ".tmp.") != NULL;
	closedir(d);
	CHECK(leftovers == 0, "%d temporary files left", leftovers);
	glint_image_free(a);
}

/* Paths are whole or refused; messages are cut visibly. */
static void test_paths_and_text(void)
{
	char buf[16], big[GLINT_PATH_MAX * 2];

	CHECK(glint_path_join(buf, sizeof(buf), "dir", "name.exr") == 0 &&
		      !strcmp(buf, "dir/name.exr"),
	      "join: '%s'", buf);
	CHECK(glint_path_join(buf, sizeof(buf), "dir", "/abs") == 0 &&
		      !strcmp(buf, "/abs"),
	      "absolute name: '%s'", buf);
	CHECK(glint_path_join(buf, sizeof(buf), "folder", "long-name.exr") ==
		      -ENAMETOOLONG,
	      "a path one byte too long is refused");
	CHECK_MSG(glint_error_msg(), "folder/long-nam");
	CHECK(glint_path_join(buf, 13, "dir", "name.exr") == 0 &&
		      !strcmp(buf, "dir/name.exr"),
	      "exactly fitting: '%s'", buf);
	CHECK(glint_path_sibling(buf, sizeof(buf), "a/env.hdr", "-m.png") ==
			      0 &&
		      !strcmp(buf, "a/env-m.png"),
	      "sibling: '%s'", buf);
	memset(big, 'x', sizeof(big) - 1);
	big[sizeof(big) - 1] = 0;
	char path[GLINT_PATH_MAX];
	CHECK(glint_path_fmt(path, sizeof(path), "%s/x", big) == -ENAMETOOLONG,
	      "an 8 KiB path is refused");
	struct glint_atomic_dir ad;
	big[GLINT_ATOMIC_DIR_PATH_MAX] = 0;
	CHECK(glint_atomic_dir_open(&ad, big) == -ENAMETOOLONG,
	      "an output folder too long for its siblings is refused");
	CHECK_MSG(glint_error_msg(), "shorter than 3840 bytes");
	big[GLINT_ATOMIC_DIR_PATH_MAX] = 'x';
	CHECK(glint_text(buf, sizeof(buf), "%s", "short") == buf &&
		      !strcmp(buf, "short"),
	      "text: '%s'", buf);
	glint_text(buf, sizeof(buf), "%s", "a label far too long");
	CHECK(!strcmp(buf, "a label far ..."), "cut text: '%s'", buf);
	glint_error_set(EINVAL, "%s", big + 100);
	glint_error_prefix(EINVAL, "file.json");
	size_t n = strlen(glint_error_msg());
	CHECK(!strncmp(glint_error_msg(), "file.json: xxx", 14) &&
		      !strcmp(glint_error_msg() + n - 3, "..."),
	      "a long message keeps its prefix and shows the cut");
}

/* A result folder never follows a symbolic link in its place. */
static void test_atomic_dir_link(void)
{
	char dir[512], target[600], link[600], note[700], file[700];
	struct glint_atomic_dir ad;

	snprintf(dir, sizeof(dir), "%s", test_tmpdir());
	snprintf(target, sizeof(target), "%s/theirs", dir);
	snprintf(link, sizeof(link), "%s/out", dir);
	snprintf(note, sizeof(note), "%s/notes.txt", target);
	CHECK(mkdir(target, 0777) == 0 && symlink(target, link) == 0, "set-up");
	FILE *f = fopen(note, "w");
	CHECK(f && fputs("mine\n", f) >= 0 && fclose(f) == 0, "note");
	static const char *const names[] = { "params.json", NULL };
	CHECK(glint_atomic_dir_check(link, names, NULL, NULL, 1) == -EEXIST,
	      "a link is refused, even with force");
	CHECK_MSG(glint_error_msg(), "is a symbolic link");
	/* A writer that gets past the check (a link made after it) fails
	 * at commit and leaves the link's target alone. */
	CHECK(glint_atomic_dir_open(&ad, link) == 0, "%s", glint_error_msg());
	glint_atomic_dir_file(&ad, "params.json", file, sizeof(file));
	f = fopen(file, "w");
	CHECK(f && fclose(f) == 0, "write into the temporary folder");
	CHECK(glint_atomic_dir_commit(&ad) == -EEXIST,
	      "commit over a link is refused");
	struct stat st;
	CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode), "the link stays");
	CHECK(access(note, R_OK) == 0, "its target's file stays");
}

int main(void)
{
	RUN(test_paths_and_text);
	RUN(test_atomic_dir_link);
	RUN(test_exr_float_roundtrip);
	RUN(test_exr_half_roundtrip);
	RUN(test_exr_window);
	RUN(test_exr_zip_equal_size);
	RUN(test_exr_tiled_read);
	RUN(test_read_window);
	RUN(test_exr_dwab);
	RUN(test_exr_dwab_offset_window);
	RUN(test_rgbe_roundtrip);
	RUN(test_pfm_roundtrip);
	RUN(test_tiff);
	RUN(test_exif);
	RUN(test_jpeg_read);
	RUN(test_png_tonemap);
	RUN(test_bad_exr);
	RUN(test_bad_rgbe);
	RUN(test_bad_pfm);
	RUN(test_header_bombs);
	RUN(test_nonfinite);
	RUN(test_write_errors);
	return test_result();
}
