/* SPDX-License-Identifier: MIT */
/*
 * OpenEXR through the OpenEXRCore C API.  What the C core of this OpenEXR
 * version cannot decode (DWAA/DWAB) is handed to exr_cxx.cpp, which uses the
 * C++ library behind a C interface.
 */
#include "atomic_file.h"
#include "error.h"
#include "exr_cxx.h"
#include "exr_internal.h"
#include "formats.h"
#include "output.h"

#include <Imath/half.h>
#include <OpenEXR/openexr.h>

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The C core reports errors through a callback; keep the last one. */
static _Thread_local char exr_last_msg[512];

static void exr_error_cb(exr_const_context_t ctx, exr_result_t code,
			 const char *msg)
{
	(void)ctx;
	snprintf(exr_last_msg, sizeof(exr_last_msg), "%s (%s)", msg,
		 exr_get_error_code_as_string(code));
}

static int exr_fail(const char *path, const char *what, exr_result_t rv)
{
	int code = rv == EXR_ERR_OUT_OF_MEMORY ? ENOMEM : EINVAL;

	if (rv == EXR_ERR_FILE_ACCESS)
		code = ENOENT;
	return glint_error_set(code, "%s: %s: %s", path, what,
			       exr_last_msg[0]
				       ? exr_last_msg
				       : exr_get_default_error_message(rv));
}

/* Channel index 0..2 for R, G, B, 3 for Y (luminance), -1 for others. */
static int channel_slot(const char *name)
{
	const char *base = strrchr(name, '.');

	base = base ? base + 1 : name;
	if (!strcmp(base, "R") || !strcmp(base, "r") || !strcmp(base, "red"))
		return 0;
	if (!strcmp(base, "G") || !strcmp(base, "g") || !strcmp(base, "green"))
		return 1;
	if (!strcmp(base, "B") || !strcmp(base, "b") || !strcmp(base, "blue"))
		return 2;
	if (!strcmp(base, "Y") || !strcmp(base, "y"))
		return 3;
	return -1;
}

/* A chunk's worth of floats that channels glint does not use are decoded
 * into: OpenEXRCore 3.1's unpackers can write through a channel left
 * without a pointer (a fuzzed file with channels "=", 0xde and Y crashed
 * it), so none is left without one. */
struct exr_scratch {
	float *p;
	size_t n;
};

/*
 * Point the decoder's channels at rows [y0, y0 + h) and columns
 * [x0, x0 + w) of img, and the others at the scratch (width x height of
 * the chunk).  Y goes to the R plane and is copied later.
 */
static exr_result_t bind_channels(exr_decode_pipeline_t *dec,
				  const exr_chunk_info_t *cinfo,
				  struct glint_image *img, int x0, int y0,
				  struct exr_scratch *sc)
{
	size_t need = (size_t)(cinfo->width > 0 ? cinfo->width : 1) *
		      (size_t)(cinfo->height > 0 ? cinfo->height : 1);
	for (int c = 0; c < dec->channel_count; c++) {
		exr_coding_channel_info_t *ch = &dec->channels[c];
		int slot = channel_slot(ch->channel_name);

		if (slot < 0) {
			if (sc->n < need) {
				float *p = realloc(sc->p, need * sizeof(float));
				if (!p)
					return EXR_ERR_OUT_OF_MEMORY;
				sc->p = p;
				sc->n = need;
			}
			ch->decode_to_ptr = (uint8_t *)sc->p;
			ch->user_pixel_stride = sizeof(float);
			ch->user_line_stride =
				(int32_t)((cinfo->width > 0 ? cinfo->width
							    : 1) *
					  sizeof(float));
			ch->user_data_type = EXR_PIXEL_FLOAT;
			ch->user_bytes_per_element = sizeof(float);
			continue;
		}
		if (slot == 3)
			slot = 0;
		ch->decode_to_ptr =
			(uint8_t *)(glint_image_px(img, x0, y0) + slot);
		ch->user_pixel_stride = 3 * sizeof(float);
		ch->user_line_stride = img->width * 3 * sizeof(float);
		ch->user_data_type = EXR_PIXEL_FLOAT;
		ch->user_bytes_per_element = sizeof(float);
	}
	return EXR_ERR_SUCCESS;
}

static exr_result_t decode_chunk(exr_context_t ctx, exr_decode_pipeline_t *dec,
				 const exr_chunk_info_t *cinfo, int *first,
				 struct glint_image *img, int x0, int y0,
				 struct exr_scratch *sc)
{
	exr_result_t rv;

	if (*first)
		rv = exr_decoding_initialize(ctx, 0, cinfo, dec);
	else
		rv = exr_decoding_update(ctx, 0, cinfo, dec);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	rv = bind_channels(dec, cinfo, img, x0, y0, sc);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	if (*first) {
		rv = exr_decoding_choose_default_routines(ctx, 0, dec);
		if (rv != EXR_ERR_SUCCESS)
			return rv;
		*first = 0;
	}
	return exr_decoding_run(ctx, 0, dec);
}

/*
 * Where decoded chunks go: straight into img (the whole data window), or,
 * for a window of it, into a chunk-sized buffer whose overlap with the
 * window is copied out: memory of the window and one chunk.
 */
struct exr_dest {
	struct glint_image *img;
	const struct glint_image_window *win; /* NULL: the whole image */
	struct glint_image *chunk;
};

/* Is the chunk at (x, y) (relative to the data window), w x h, needed? */
static int chunk_wanted(const struct exr_dest *d, int x, int y, int w, int h)
{
	const struct glint_image_window *v = d->win;

	return !v || (x < v->x + v->width && x + w > v->x &&
		      y < v->y + v->height && y + h > v->y);
}

static exr_result_t decode_into(exr_context_t ctx, exr_decode_pipeline_t *dec,
				const exr_chunk_info_t *cinfo, int *first,
				struct exr_dest *d, int x, int y,
				struct exr_scratch *sc)
{
	const struct glint_image_window *v = d->win;
	int w = cinfo->width, h = cinfo->height;

	if (!v)
		return decode_chunk(ctx, dec, cinfo, first, d->img, x, y, sc);
	if (!d->chunk || d->chunk->width != w || d->chunk->height < h) {
		glint_image_free(d->chunk);
		d->chunk = glint_image_new(w, h);
		if (!d->chunk)
			return EXR_ERR_OUT_OF_MEMORY;
	}
	exr_result_t rv =
		decode_chunk(ctx, dec, cinfo, first, d->chunk, 0, 0, sc);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	int x0 = x > v->x ? x : v->x, y0 = y > v->y ? y : v->y;
	int x1 = x + w < v->x + v->width ? x + w : v->x + v->width;
	int y1 = y + h < v->y + v->height ? y + h : v->y + v->height;
	for (int yy = y0; yy < y1; yy++)
		memcpy(glint_image_px(d->img, x0 - v->x, yy - v->y),
		       glint_image_px(d->chunk, x0 - x, yy - y),
		       (size_t)(x1 - x0) * 3 * sizeof(float));
	return EXR_ERR_SUCCESS;
}

static exr_result_t read_scanlines(exr_context_t ctx,
				   const exr_attr_box2i_t *dw,
				   struct exr_dest *d, int *failed_y)
{
	exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
	struct exr_scratch sc = { NULL, 0 };
	exr_result_t rv;
	int32_t lines;
	int first = 1;

	rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	int width = dw->max.x - dw->min.x + 1;
	for (int y = dw->min.y; y <= dw->max.y; y += lines) {
		exr_chunk_info_t cinfo;

		if (!chunk_wanted(d, 0, y - dw->min.y, width, lines))
			continue;
		*failed_y = y;
		rv = exr_read_scanline_chunk_info(ctx, 0, y, &cinfo);
		if (rv != EXR_ERR_SUCCESS)
			break;
		rv = decode_into(ctx, &dec, &cinfo, &first, d, 0,
				 cinfo.start_y - dw->min.y, &sc);
		if (rv != EXR_ERR_SUCCESS)
			break;
	}
	exr_decoding_destroy(ctx, &dec);
	free(sc.p);
	return rv;
}

static exr_result_t read_tiles(exr_context_t ctx, struct exr_dest *d,
			       int *failed_y)
{
	exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
	struct exr_scratch sc = { NULL, 0 };
	int32_t tw, th, lw, lh;
	exr_result_t rv;
	int first = 1;

	rv = exr_get_tile_sizes(ctx, 0, 0, 0, &tw, &th);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_get_level_sizes(ctx, 0, 0, 0, &lw, &lh);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	int nx = (lw + tw - 1) / tw, ny = (lh + th - 1) / th;
	/* Level 0 is the full-resolution image for every level mode. */
	for (int ty = 0; ty < ny && rv == EXR_ERR_SUCCESS; ty++) {
		for (int tx = 0; tx < nx; tx++) {
			exr_chunk_info_t cinfo;

			if (!chunk_wanted(d, tx * tw, ty * th, tw, th))
				continue;
			*failed_y = ty * (int)th;
			rv = exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0,
						      &cinfo);
			if (rv != EXR_ERR_SUCCESS)
				break;
			rv = decode_into(ctx, &dec, &cinfo, &first, d,
					 tx * (int)tw, ty * (int)th, &sc);
			if (rv != EXR_ERR_SUCCESS)
				break;
		}
	}
	exr_decoding_destroy(ctx, &dec);
	free(sc.p);
	return rv;
}

/* Which of R, G, B, Y the part has; error when it has none usable. */
static int check_channels(exr_context_t ctx, const char *path, int *has_y)
{
	const exr_attr_chlist_t *chl;
	int found[4] = { 0 };
	exr_result_t rv = exr_get_channels(ctx, 0, &chl);

	if (rv != EXR_ERR_SUCCESS)
		return exr_fail(path, "reading the channel list", rv);
	for (int i = 0; i < chl->num_channels; i++) {
		const exr_attr_chlist_entry_t *e = &chl->entries[i];
		int slot = channel_slot(e->name.str);

		if (slot < 0)
			continue;
		if (e->x_sampling != 1 || e->y_sampling != 1)
			return glint_error_set(
				EINVAL,
				"%s: channel %s is subsampled (%dx%d): "
				"expected full-resolution R, G, B or Y",
				path, e->name.str, e->x_sampling,
				e->y_sampling);
		found[slot] = 1;
	}
	if (found[0] && found[1] && found[2]) {
		*has_y = 0;
		return 0;
	}
	if (found[3]) {
		*has_y = 1;
		return 0;
	}
	return glint_error_set(EINVAL,
			       "%s: has %d channels but not R, G and B (or Y)",
			       path, chl->num_channels);
}

/*
 * The fewest bytes a data window can be stored in: 2 bytes a pixel (one
 * half channel) uncompressed; compressed, deflate's best case (1032:1)
 * bounds every codec glint reads.
 */
static double min_data_bytes(const exr_attr_box2i_t *dw, exr_compression_t comp)
{
	double px = ((double)dw->max.x - dw->min.x + 1) *
		    ((double)dw->max.y - dw->min.y + 1);
	return comp == EXR_COMPRESSION_NONE ? 2 * px : 2 * px / 1032;
}

/* win: NULL, or a window of the data window to read alone (checked to
 * lie inside it). */
static int exr_read_core(const char *path, const struct glint_image_window *win,
			 struct glint_image **out)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	exr_context_t ctx = NULL;
	exr_attr_box2i_t dw;
	exr_storage_t storage;
	exr_compression_t comp;
	struct glint_image *img = NULL;
	int has_y = 0, failed_y = 0, ret;
	exr_result_t rv;

	init.error_handler_fn = exr_error_cb;
	exr_last_msg[0] = '\0';
	rv = exr_start_read(&ctx, path, &init);
	if (rv != EXR_ERR_SUCCESS) {
		ret = exr_fail(path, "not a readable OpenEXR file", rv);
		goto out;
	}
	rv = exr_get_storage(ctx, 0, &storage);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_get_data_window(ctx, 0, &dw);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_get_compression(ctx, 0, &comp);
	if (rv != EXR_ERR_SUCCESS) {
		ret = exr_fail(path, "reading the header", rv);
		goto out;
	}
	ret = glint_image_size_check(
		path, "dataWindow", (long long)dw.max.x - dw.min.x + 1,
		(long long)dw.max.y - dw.min.y + 1, glint_file_size(path),
		min_data_bytes(&dw, comp));
	if (ret < 0)
		goto out;
	if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
		ret = glint_error_set(EINVAL,
				      "%s: deep EXR data: expected a flat "
				      "scanline or tiled image",
				      path);
		goto out;
	}
	if (comp == EXR_COMPRESSION_DWAA || comp == EXR_COMPRESSION_DWAB) {
		ret = 1; /* C core cannot decode: caller falls back */
		goto out;
	}
	ret = check_channels(ctx, path, &has_y);
	if (ret < 0)
		goto out;
	int dw_w = dw.max.x - dw.min.x + 1, dw_h = dw.max.y - dw.min.y + 1;
	if (win) {
		ret = glint_image_window_check(path, win, dw_w, dw_h);
		if (ret < 0)
			goto out;
	}
	img = win ? glint_image_new(win->width, win->height)
		  : glint_image_new(dw_w, dw_h);
	if (!img) {
		ret = glint_error_prefix(EINVAL, "%s: data window", path);
		goto out;
	}
	struct exr_dest dest = { img, win, NULL };
	if (storage == EXR_STORAGE_SCANLINE)
		rv = read_scanlines(ctx, &dw, &dest, &failed_y);
	else
		rv = read_tiles(ctx, &dest, &failed_y);
	glint_image_free(dest.chunk);
	if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED) {
		ret = 1;
		goto out;
	}
	if (rv != EXR_ERR_SUCCESS) {
		char what[64];
		snprintf(what, sizeof(what), "pixel data near row %d",
			 failed_y);
		ret = exr_fail(path, what, rv);
		goto out;
	}
	if (has_y) {
		size_t n = (size_t)img->width * img->height;
		for (size_t i = 0; i < n; i++)
			img->data[3 * i + 1] = img->data[3 * i + 2] =
				img->data[3 * i];
	}
	*out = img;
	img = NULL;
	ret = 0;
out:
	glint_image_free(img);
	if (ctx)
		exr_finish(&ctx);
	return ret;
}

int glint_exr_read_window(const char *path,
			  const struct glint_image_window *win,
			  struct glint_image **out)
{
	int ret;

	*out = NULL;
	if (access(path, R_OK) < 0)
		return glint_error_set(errno, "%s: cannot open: %s", path,
				       strerror(errno));
	ret = exr_read_core(path, win, out);
	if (ret <= 0)
		return ret;
	/* DWA: the C++ library reads it whole. */
	ret = glint_exr_check_attribute_sizes(path);
	if (ret == 0)
		ret = glint_exr_read_cxx(path, out);
	if (ret < 0 || !win)
		return ret;
	return glint_image_window_take(path, win, out);
}

int glint_exr_size(const char *path, int *width, int *height)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	exr_context_t ctx = NULL;
	exr_attr_box2i_t dw;
	exr_result_t rv;
	int ret = 0;

	init.error_handler_fn = exr_error_cb;
	exr_last_msg[0] = '\0';
	rv = exr_start_read(&ctx, path, &init);
	if (rv != EXR_ERR_SUCCESS)
		ret = exr_fail(path, "not a readable OpenEXR file", rv);
	else if ((rv = exr_get_data_window(ctx, 0, &dw)) != EXR_ERR_SUCCESS)
		ret = exr_fail(path, "reading the header", rv);
	else {
		long long w = (long long)dw.max.x - dw.min.x + 1;
		long long h = (long long)dw.max.y - dw.min.y + 1;

		if (w < 1 || h < 1 || w > INT_MAX || h > INT_MAX)
			ret = glint_error_set(EINVAL,
					      "%s: dataWindow %lld x %lld is "
					      "not a valid size",
					      path, w, h);
		else {
			*width = (int)w;
			*height = (int)h;
		}
	}
	if (ctx)
		exr_finish(&ctx);
	return ret;
}

int glint_exr_software(const char *path, char *buf, size_t n)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	exr_context_t ctx = NULL;
	const char *s = NULL;
	int32_t len = 0;
	exr_result_t rv;
	int ret = -ENOENT;

	init.error_handler_fn = exr_error_cb;
	exr_last_msg[0] = '\0';
	rv = exr_start_read(&ctx, path, &init);
	if (rv != EXR_ERR_SUCCESS)
		ret = exr_fail(path, "not a readable OpenEXR file", rv);
	else if (exr_attr_get_string(ctx, 0, "software", &len, &s) ==
			 EXR_ERR_SUCCESS &&
		 s && len >= 0) {
		snprintf(buf, n, "%.*s", (int)len, s);
		ret = 0;
	}
	if (ctx)
		exr_finish(&ctx);
	return ret;
}

int glint_exr_read(const char *path, struct glint_image **out)
{
	return glint_exr_read_window(path, NULL, out);
}

/*
 * OpenEXRCore 3.1.5 stores zlib output that is exactly as large as the
 * packed data as if it were compressed, but readers take a chunk whose
 * stored size equals its unpacked size as raw: rare chunks come back as
 * garbage (upstream issue #2306, fixed in 2026 by PR #2307; seen here on a
 * 64x48 render).  Store such chunks raw, as the fixed library does.
 */
typedef exr_result_t (*exr_compress_fn)(exr_encode_pipeline_t *);

static exr_result_t compress_or_store(exr_encode_pipeline_t *enc)
{
	exr_compress_fn zip = (exr_compress_fn)enc->encoding_user_data;
	exr_result_t rv = zip(enc);

	if (rv == EXR_ERR_SUCCESS &&
	    enc->compressed_bytes >= enc->packed_bytes &&
	    enc->compressed_buffer != enc->packed_buffer) {
		memcpy(enc->compressed_buffer, enc->packed_buffer,
		       enc->packed_bytes);
		enc->compressed_bytes = enc->packed_bytes;
	}
	return rv;
}

static int encode_rows(exr_context_t ctx, int part, const uint8_t *base,
		       int pixel_stride, int width, int height, int y0,
		       exr_pixel_type_t type)
{
	exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
	exr_result_t rv = EXR_ERR_SUCCESS;
	int32_t lines;
	int first = 1;

	rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
	for (int y = 0; y < height && rv == EXR_ERR_SUCCESS; y += lines) {
		exr_chunk_info_t cinfo;

		rv = exr_write_scanline_chunk_info(ctx, part, y0 + y, &cinfo);
		if (rv != EXR_ERR_SUCCESS)
			break;
		if (first)
			rv = exr_encoding_initialize(ctx, part, &cinfo, &enc);
		else
			rv = exr_encoding_update(ctx, part, &cinfo, &enc);
		if (rv != EXR_ERR_SUCCESS)
			break;
		for (int c = 0; c < enc.channel_count; c++) {
			exr_coding_channel_info_t *ch = &enc.channels[c];
			int slot = channel_slot(ch->channel_name);
			size_t elem = type == EXR_PIXEL_HALF ? 2 : 4;

			ch->encode_from_ptr =
				base +
				((size_t)y * width * 3 + (size_t)slot) * elem;
			ch->user_pixel_stride = pixel_stride;
			ch->user_line_stride = pixel_stride * width;
			ch->user_data_type = type;
			ch->user_bytes_per_element = (int16_t)elem;
		}
		if (first) {
			rv = exr_encoding_choose_default_routines(ctx, part,
								  &enc);
			first = 0;
			if (rv != EXR_ERR_SUCCESS)
				break;
			if (enc.compress_fn) {
				enc.encoding_user_data =
					(void *)enc.compress_fn;
				enc.compress_fn = compress_or_store;
			}
		}
		rv = exr_encoding_run(ctx, part, &enc);
	}
	exr_encoding_destroy(ctx, &enc);
	return rv;
}

int glint_exr_write(const char *path, const struct glint_image *img,
		    const struct glint_write_opts *opts)
{
	int half = opts->exr_half;
	exr_attr_box2i_t dw, disp;
	dw.min.x = opts->window_x;
	dw.min.y = opts->window_y;
	dw.max.x = opts->window_x + img->width - 1;
	dw.max.y = opts->window_y + img->height - 1;
	disp.min.x = disp.min.y = 0;
	disp.max.x = opts->frame_width - 1;
	disp.max.y = opts->frame_height - 1;
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	exr_pixel_type_t type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
	static const char *names[3] = { "R", "G", "B" };
	exr_context_t ctx = NULL;
	uint16_t *halfbuf = NULL;
	const uint8_t *base = (const uint8_t *)img->data;
	char tmp[4096];
	int part, ret;
	exr_result_t rv;

	if (opts->frame_width &&
	    (opts->window_x < 0 || opts->window_y < 0 ||
	     dw.max.x >= opts->frame_width || dw.max.y >= opts->frame_height))
		return glint_error_set(EINVAL,
				       "%s: a %dx%d window at (%d, %d) does "
				       "not lie inside the %dx%d frame",
				       path, img->width, img->height,
				       opts->window_x, opts->window_y,
				       opts->frame_width, opts->frame_height);
	ret = glint_atomic_tmpname(path, tmp, sizeof(tmp));
	if (ret < 0)
		return ret;
	if (half) {
		size_t n = (size_t)img->width * img->height * 3;
		halfbuf = malloc(n * sizeof(uint16_t));
		if (!halfbuf) {
			ret = glint_error_set(ENOMEM, "%s: out of memory",
					      path);
			goto err;
		}
		for (size_t i = 0; i < n; i++)
			halfbuf[i] = imath_float_to_half(img->data[i]);
		base = (const uint8_t *)halfbuf;
	}
	init.error_handler_fn = exr_error_cb;
	exr_last_msg[0] = '\0';
	rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_add_part(ctx, "rgb", EXR_STORAGE_SCANLINE, &part);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_initialize_required_attr_simple(ctx, part, img->width,
							 img->height,
							 EXR_COMPRESSION_ZIP);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_attr_set_string(ctx, part, "software",
					 GLINT_OUTPUT_SOFTWARE);
	if (rv == EXR_ERR_SUCCESS && opts->frame_width) {
		rv = exr_set_data_window(ctx, part, &dw);
		if (rv == EXR_ERR_SUCCESS)
			rv = exr_set_display_window(ctx, part, &disp);
	}
	for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; c++)
		rv = exr_add_channel(ctx, part, names[c], type,
				     EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_write_header(ctx);
	if (rv == EXR_ERR_SUCCESS)
		rv = encode_rows(ctx, part, base, half ? 6 : 12, img->width,
				 img->height, opts->frame_width ? dw.min.y : 0,
				 type);
	if (rv != EXR_ERR_SUCCESS) {
		ret = exr_fail(path, "writing", rv);
		goto err;
	}
	rv = exr_finish(&ctx);
	ctx = NULL;
	if (rv != EXR_ERR_SUCCESS) {
		ret = exr_fail(path, "finishing", rv);
		goto err;
	}
	free(halfbuf);
	return glint_atomic_rename(tmp, path);
err:
	if (ctx)
		exr_finish(&ctx);
	unlink(tmp);
	free(halfbuf);
	return ret;
}
