/* SPDX-License-Identifier: MIT */
/* Raw frames from any camera's files (raw_file.h). */
#include "capture/hdr/raw_file.h"

#include "capture/hdr/frame_file.h"
#include "core/error.h"
#include "core/exif.h"
#include "core/image.h"
#include "core/path.h"
#include "core/tiff.h"

#include <errno.h>
#include <jansson.h>
#include <libraw/libraw.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void info_init(struct glint_raw_info *info, const char *reader)
{
	memset(info, 0, sizeof(*info));
	snprintf(info->reader, sizeof(info->reader), "%s", reader);
	info->rgb_cam[0] = info->rgb_cam[4] = info->rgb_cam[8] = 1;
}

/* A DNG or PNG holding glint's own frame metadata (the JSON frame_file.h
 * writes, with its pixels' checksum). */
static int is_glint_frame(const char *path, const char *ext)
{
	if (!strcmp(ext, "png"))
		return 1;
	if (strcmp(ext, "dng"))
		return 0;
	struct glint_tiff_msgs m;
	TIFF *tif = glint_tiff_open(path, "r", &m);
	const char *desc = NULL;
	int glint = 0;
	if (!tif)
		return 0;
	if (TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc) {
		json_t *doc = json_loads(desc, 0, NULL);
		glint = json_is_object(doc) &&
			json_object_get(doc, "pixels_crc32") != NULL;
		json_decref(doc);
	}
	TIFFClose(tif);
	return glint;
}

static int read_tiff16(const char *path, struct glint_frame *f,
		       struct glint_raw_info *info)
{
	int w, h, nc;
	uint16_t *px;
	int ret = glint_tiff_read_rgb16(path, &w, &h, &nc, &px);

	if (ret < 0)
		return ret;
	info_init(info, "libtiff");
	f->width = w;
	f->height = h;
	f->channels = nc;
	snprintf(f->format, sizeof(f->format), "%s",
		 nc == 3 ? "RGB16" : "MONO16");
	snprintf(f->source_format, sizeof(f->source_format), "TIFF16");
	f->bit_depth = 16;
	f->linear = 1;
	f->data = px;
	f->gain = 1;
	double t = 0, iso = 0;
	if (glint_exif_exposure(path, &t, &iso) == 0) {
		f->exposure_s = t;
		info->has_exposure = 1;
	}
	if (iso > 0) {
		info->iso = iso;
		f->gain = iso / 100;
	}
	return 0;
}

/* The colour of the visible area's site (row, col): 0 R, 1 G, 2 B (LibRaw's
 * second green, 3, is green). */
static int site_colour(libraw_data_t *lr, int row, int col)
{
	int c = libraw_COLOR(lr, row, col);
	return c == 3 ? 1 : c;
}

/* The 2 x 2 cell's layout name, or NULL when the mosaic does not repeat
 * every 2 x 2 sites or is not one red, two greens and one blue. */
static const char *bayer_layout(libraw_data_t *lr)
{
	static const char *const names[] = { "RGGB16", "GRBG16", "GBRG16",
					     "BGGR16" };
	static const int cells[4][4] = {
		{ 0, 1, 1, 2 }, { 1, 0, 2, 1 }, { 1, 2, 0, 1 }, { 2, 1, 1, 0 }
	};
	int cell[4];

	if (lr->idata.colors != 3 || lr->idata.filters < 1000)
		return NULL;
	for (int k = 0; k < 4; k++)
		cell[k] = site_colour(lr, k >> 1, k & 1);
	for (int y = 0; y < 16; y++)
		for (int x = 0; x < 16; x++)
			if (site_colour(lr, y, x) !=
			    cell[(y & 1) * 2 + (x & 1)])
				return NULL;
	for (int i = 0; i < 4; i++)
		if (!memcmp(cell, cells[i], sizeof(cell)))
			return names[i];
	return NULL;
}

/* LibRaw's black level of the visible area's site (row, col) of colour c:
 * the common level, the colour's own, and the repeat pattern's. */
static unsigned site_black(const libraw_colordata_t *col, int row, int x, int c)
{
	unsigned b = col->black + col->cblack[c];
	unsigned ph = col->cblack[4], pw = col->cblack[5];
	if (ph && pw && 6 + ph * pw <= LIBRAW_CBLACK_SIZE)
		b += col->cblack[6 + (row % ph) * pw + x % pw];
	return b;
}

/* The camera -> linear sRGB matrix: rgb_cam x diag(pre_mul / pre_mul[1]). */
static void colour_matrix(libraw_data_t *lr, struct glint_raw_info *info)
{
	const libraw_colordata_t *c = &lr->color;
	int known = 0;
	/* A matrix LibRaw knows: a DNG's ColorMatrix, a camera's entry in
	 * its table (cam_xyz), or an rgb_cam that is not its identity
	 * default. */
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			known |= c->cam_xyz[i][j] != 0 ||
				 c->dng_color[0].colormatrix[i][j] != 0 ||
				 c->dng_color[1].colormatrix[i][j] != 0 ||
				 fabs(c->rgb_cam[i][j] - (i == j)) > 1e-6;
	if (!known || lr->idata.colors != 3 || !(c->pre_mul[1] > 0))
		return;
	for (int j = 0; j < 3; j++)
		if (!(c->pre_mul[j] > 0) || !isfinite(c->pre_mul[j]))
			return;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			info->rgb_cam[3 * i + j] = c->rgb_cam[i][j] *
						   c->pre_mul[j] /
						   c->pre_mul[1];
	info->has_matrix = 1;
}

/* The visible area's samples (n a pixel: 1 from raw_image, 3 from a
 * colour image of `stride` samples a pixel) with each site's black
 * brought to the lowest; *black that lowest. */
static int copy_visible(libraw_data_t *lr, const char *path, int n, int stride,
			int bayer, struct glint_frame *f)
{
	const libraw_image_sizes_t *s = &lr->rawdata.sizes;
	const uint16_t *src = lr->rawdata.raw_image;
	if (!src)
		src = lr->rawdata.color3_image
			      ? &lr->rawdata.color3_image[0][0]
			      : &lr->rawdata.color4_image[0][0];
	size_t pitch = s->raw_pitch / sizeof(uint16_t);
	int w = s->width, h = s->height;
	unsigned lo = ~0u;

	if (!pitch || (size_t)s->left_margin + w > pitch / (size_t)stride ||
	    s->top_margin + h > s->raw_height)
		return glint_error_set(EINVAL,
				       "%s: LibRaw's visible area (%dx%d at "
				       "%d,%d) lies outside its raw image",
				       path, w, h, s->left_margin,
				       s->top_margin);
	/* The lowest over a block as large as any repeat pattern. */
	for (int y = 0; y < 64 && y < h; y++)
		for (int x = 0; x < 64 && x < w; x++)
			for (int c = 0; c < n; c++) {
				unsigned b = site_black(
					&lr->color, y, x,
					bayer ? site_colour(lr, y, x) : c);
				lo = b < lo ? b : lo;
			}
	f->data = malloc((size_t)w * h * n * sizeof(uint16_t));
	if (!f->data)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	for (int y = 0; y < h; y++) {
		const uint16_t *row = src +
				      (size_t)(y + s->top_margin) * pitch +
				      (size_t)s->left_margin * stride;
		uint16_t *out = f->data + (size_t)y * w * n;
		for (int x = 0; x < w; x++)
			for (int c = 0; c < n; c++) {
				unsigned b = site_black(
					&lr->color, y, x,
					bayer ? site_colour(lr, y, x) : c);
				unsigned v = row[(size_t)x * stride + c];
				b = b > lo ? b - lo : 0;
				out[(size_t)x * n + c] =
					(uint16_t)(v > b ? v - b : 0);
			}
	}
	f->black_level = lo;
	return 0;
}

/* LibRaw's word on data it could not decode (by default printed to
 * stderr): the first one kept, the frame refused. */
struct data_error {
	int count;
	int offset; /* -1: the file ended early */
};

static void on_data_error(void *ctx, const char *file, const int offset)
{
	struct data_error *d = ctx;
	(void)file;
	if (!d->count++)
		d->offset = offset;
}

static const char *libraw_msg(int e)
{
	return e > 0 ? strerror(e) : libraw_strerror(e);
}

static int read_libraw(const char *path, struct glint_frame *f,
		       struct glint_raw_info *info)
{
	libraw_data_t *lr = libraw_init(0);
	struct data_error derr = { 0, 0 };
	int ret = 0, e;

	if (!lr)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	libraw_set_dataerror_handler(lr, on_data_error, &derr);
	info_init(info, "LibRaw");
	snprintf(info->reader, sizeof(info->reader), "LibRaw %s",
		 libraw_version());
	e = libraw_open_file(lr, path);
	if (e != LIBRAW_SUCCESS) {
		ret = glint_error_set(EINVAL,
				      "%s: not a raw file LibRaw reads (%s): "
				      "expected a camera's raw file or DNG, "
				      "a 16-bit TIFF, or 8-bit photos with "
				      "their exposure times",
				      path, libraw_msg(e));
		goto out;
	}
	const libraw_image_sizes_t *s = &lr->sizes;
	long long bytes = glint_file_size(path);
	/* Sizes from the header, checked before LibRaw unpacks: glint's image
	 * limits, and no more than 64 sites a byte of the file (lossless
	 * raw codecs reach 2 or 3). */
	ret = glint_image_size_check(path, "raw image size", s->raw_width,
				     s->raw_height, bytes,
				     (double)s->raw_width * s->raw_height / 64);
	if (ret == 0 && (s->width < 2 || s->height < 2))
		ret = glint_error_set(EINVAL, "%s: a %dx%d raw image", path,
				      s->width, s->height);
	if (ret < 0)
		goto out;
	e = libraw_unpack(lr);
	if (e != LIBRAW_SUCCESS || derr.count) {
		char where[48] = "";
		if (derr.count && derr.offset >= 0)
			snprintf(where, sizeof(where), " at byte %d",
				 derr.offset);
		ret = glint_error_set(EIO,
				      "%s: its raw data is truncated or "
				      "corrupt (LibRaw: %s%s)",
				      path,
				      derr.count && derr.offset < 0
					      ? "unexpected end of file"
				      : derr.count ? "bad data"
						   : libraw_msg(e),
				      where);
		goto out;
	}
	snprintf(info->camera, sizeof(info->camera), "%s %s", lr->idata.make,
		 lr->idata.model);
	const char *layout = NULL;
	int n = 1, stride = 1, bayer = 0;
	if (lr->rawdata.raw_image && lr->idata.filters) {
		layout = bayer_layout(lr);
		bayer = 1;
		if (!layout) {
			ret = glint_error_set(
				EINVAL,
				"%s: a %s mosaic (LibRaw filters 0x%x, colours "
				"%s): glint merges 2 x 2 Bayer (RGGB, GRBG, "
				"GBRG, BGGR), linear RGB and monochrome raw "
				"data",
				path,
				lr->idata.filters == 9 ? "Fujifilm X-Trans"
						       : "non-Bayer",
				lr->idata.filters, lr->idata.cdesc);
			goto out;
		}
	} else if (lr->rawdata.raw_image && lr->idata.colors == 1) {
		layout = "MONO16";
	} else if ((lr->rawdata.color3_image || lr->rawdata.color4_image) &&
		   lr->idata.colors == 3) {
		layout = "RGB16";
		n = 3;
		stride = lr->rawdata.color3_image ? 3 : 4;
	} else {
		ret = glint_error_set(EINVAL,
				      "%s: raw data of %d colours that is "
				      "neither a Bayer mosaic, linear RGB nor "
				      "monochrome (%s)",
				      path, lr->idata.colors,
				      libraw_unpack_function_name(lr));
		goto out;
	}
	const libraw_colordata_t *col = &lr->color;
	if (!(col->maximum > 0) || col->maximum > 65535) {
		ret = glint_error_set(EINVAL, "%s: white level %u", path,
				      col->maximum);
		goto out;
	}
	f->width = s->width;
	f->height = s->height;
	f->channels = n;
	snprintf(f->format, sizeof(f->format), "%s", layout);
	snprintf(f->source_format, sizeof(f->source_format), "LibRaw");
	f->linear = 1;
	f->white_level = col->maximum;
	f->bit_depth = 1;
	while (f->bit_depth < 16 && (1u << f->bit_depth) - 1 < col->maximum)
		f->bit_depth++;
	ret = copy_visible(lr, path, n, stride, bayer, f);
	if (ret < 0)
		goto out;
	/* Values above the white level count as clipped; none may pass the
	 * bit depth's top code. */
	unsigned top = (1u << f->bit_depth) - 1;
	for (size_t i = 0; i < (size_t)f->width * f->height * n; i++)
		if (f->data[i] > top)
			f->data[i] = (uint16_t)top;
	if (!(f->black_level < f->white_level)) {
		ret = glint_error_set(EINVAL,
				      "%s: black level %g at or above the "
				      "white level %g",
				      path, f->black_level, f->white_level);
		goto out;
	}
	f->gain = 1;
	if (lr->other.iso_speed > 0 && isfinite(lr->other.iso_speed)) {
		info->iso = lr->other.iso_speed;
		f->gain = info->iso / 100;
	}
	if (lr->other.shutter > 0 && isfinite(lr->other.shutter)) {
		f->exposure_s = lr->other.shutter;
		info->has_exposure = 1;
	}
	colour_matrix(lr, info);
out:
	if (ret < 0)
		glint_frame_release(f);
	libraw_close(lr);
	return ret;
}

int glint_raw_file_read(const char *path, struct glint_frame *f,
			struct glint_raw_info *info)
{
	char ext[16];

	memset(f, 0, sizeof(*f));
	/* LibRaw and libtiff open by path: a FIFO or a device is refused
	 * first rather than blocking them */
	int reg = glint_check_regular(path);
	if (reg < 0)
		return reg;
	glint_path_ext(path, ext, sizeof(ext));
	if (is_glint_frame(path, ext)) {
		info_init(info, "glint frame");
		snprintf(info->camera, sizeof(info->camera), "glint camera");
		int ret = glint_frame_read(path, f, NULL);
		info->has_exposure = ret == 0;
		info->iso = 100 * f->gain;
		return ret;
	}
	if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		return read_tiff16(path, f, info);
	return read_libraw(path, f, info);
}

static int png_bits(const char *path)
{
	unsigned char head[33];
	FILE *fp = glint_fopen_regular(path, "rb");
	if (!fp)
		return -errno;
	size_t n = fread(head, 1, sizeof(head), fp);
	fclose(fp);
	if (n < sizeof(head) || png_sig_cmp(head, 0, 8) ||
	    memcmp(head + 12, "IHDR", 4))
		return glint_error_set(EINVAL, "%s: not a PNG", path);
	return head[24]; /* IHDR's bit depth */
}

int glint_raw_file_is_8bit(const char *path)
{
	char ext[16];
	int bits;

	int reg = glint_check_regular(path);
	if (reg < 0)
		return reg;
	glint_path_ext(path, ext, sizeof(ext));
	if (!strcmp(ext, "jpg") || !strcmp(ext, "jpeg"))
		return 1;
	if (!strcmp(ext, "png"))
		bits = png_bits(path);
	else if (!strcmp(ext, "tif") || !strcmp(ext, "tiff"))
		bits = glint_tiff_sample_bits(path);
	else
		return 0;
	return bits < 0 ? bits : bits <= 8;
}
