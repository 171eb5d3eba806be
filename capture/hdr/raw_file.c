/* SPDX-License-Identifier: MIT */
/* Raw frames from any camera's files (raw_file.h). */
#define _GNU_SOURCE /* pipe2, strsignal */
#include "capture/hdr/raw_file.h"

#include "capture/hdr/frame_file.h"
#include "core/error.h"
#include "core/exif.h"
#include "core/image.h"
#include "core/path.h"
#include "core/tiff.h"

#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <libraw/libraw.h>
#include <math.h>
#include <png.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

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

/*
 * LibRaw runs in a child process.  Its parsers are the one part of glint's
 * readers that glint does not own, and Debian's LibRaw 0.20 aborts (a
 * fortified strcat in its Hasselblad model parser, found by the fuzz suite)
 * or faults on some hostile files: a crash there must cost a refused file,
 * not the daemon or a user's session.  The child opens and unpacks the file
 * and sends what glint needs of it through a pipe: the facts below, then
 * the visible area's samples.  Every check and allocation of glint's own
 * (layout, black levels, white level, sizes) runs in the caller, on data it
 * validates before it allocates.
 */
struct raw_decoded {
	int ret; /* 0, or a negative errno with msg */
	char msg[512];
	int raw_width, raw_height;
	int width, height; /* the visible area */
	int stride;	   /* samples a pixel sent: 1, 3 or 4 */
	int kind;	   /* 1 raw_image, 3 color3_image, 4 color4_image */
	int colors;
	unsigned filters;
	char cdesc[5];
	char make[64], model[64];
	char unpacker[64];
	signed char colour[16][16]; /* libraw_COLOR over a 16 x 16 block */
	unsigned black, maximum;
	unsigned cblack[LIBRAW_CBLACK_SIZE];
	float pre_mul[4];
	float rgb_cam[3][4];
	float cam_xyz[4][3];
	float dng_matrix[2][4][3];
	float iso, shutter;
};

/* The colour of the visible area's site (row, col): 0 R, 1 G, 2 B (LibRaw's
 * second green, 3, is green).  A mosaic is accepted only when it repeats
 * every 2 x 2 sites over the whole 16 x 16 block, so the block holds it. */
static int site_colour(const struct raw_decoded *d, int row, int col)
{
	int c = d->colour[row & 15][col & 15];
	return c == 3 ? 1 : c;
}

/* The 2 x 2 cell's layout name, or NULL when the mosaic does not repeat
 * every 2 x 2 sites or is not one red, two greens and one blue. */
static const char *bayer_layout(const struct raw_decoded *d)
{
	static const char *const names[] = { "RGGB16", "GRBG16", "GBRG16",
					     "BGGR16" };
	static const int cells[4][4] = {
		{ 0, 1, 1, 2 }, { 1, 0, 2, 1 }, { 1, 2, 0, 1 }, { 2, 1, 1, 0 }
	};
	int cell[4];

	if (d->colors != 3 || d->filters < 1000)
		return NULL;
	for (int k = 0; k < 4; k++)
		cell[k] = site_colour(d, k >> 1, k & 1);
	for (int y = 0; y < 16; y++)
		for (int x = 0; x < 16; x++)
			if (site_colour(d, y, x) != cell[(y & 1) * 2 + (x & 1)])
				return NULL;
	for (int i = 0; i < 4; i++)
		if (!memcmp(cell, cells[i], sizeof(cell)))
			return names[i];
	return NULL;
}

/* LibRaw's black level of the visible area's site (row, col) of colour c:
 * the common level, the colour's own, and the repeat pattern's. */
static unsigned site_black(const struct raw_decoded *d, int row, int x, int c)
{
	unsigned b = d->black + d->cblack[c];
	unsigned ph = d->cblack[4], pw = d->cblack[5];
	if (ph && pw && ph <= LIBRAW_CBLACK_SIZE && pw <= LIBRAW_CBLACK_SIZE &&
	    6 + ph * pw <= LIBRAW_CBLACK_SIZE)
		b += d->cblack[6 + (row % ph) * pw + x % pw];
	return b;
}

/* The camera -> linear sRGB matrix: rgb_cam x diag(pre_mul / pre_mul[1]). */
static void colour_matrix(const struct raw_decoded *d,
			  struct glint_raw_info *info)
{
	int known = 0;
	/* A matrix LibRaw knows: a DNG's ColorMatrix, a camera's entry in
	 * its table (cam_xyz), or an rgb_cam that is not its identity
	 * default. */
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			known |= d->cam_xyz[i][j] != 0 ||
				 d->dng_matrix[0][i][j] != 0 ||
				 d->dng_matrix[1][i][j] != 0 ||
				 fabs(d->rgb_cam[i][j] - (i == j)) > 1e-6;
	if (!known || d->colors != 3 || !(d->pre_mul[1] > 0))
		return;
	for (int j = 0; j < 3; j++)
		if (!(d->pre_mul[j] > 0) || !isfinite(d->pre_mul[j]))
			return;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			info->rgb_cam[3 * i + j] = d->rgb_cam[i][j] *
						   d->pre_mul[j] /
						   d->pre_mul[1];
	info->has_matrix = 1;
}

/* The visible area's samples (n a pixel of the `stride` sent) with each
 * site's black brought to the lowest; *black that lowest. */
static int copy_visible(const struct raw_decoded *d, const uint16_t *src, int n,
			int bayer, struct glint_frame *f)
{
	int w = d->width, h = d->height;
	unsigned lo = ~0u;

	/* The lowest over a block as large as any repeat pattern. */
	for (int y = 0; y < 64 && y < h; y++)
		for (int x = 0; x < 64 && x < w; x++)
			for (int c = 0; c < n; c++) {
				unsigned b = site_black(
					d, y, x,
					bayer ? site_colour(d, y, x) : c);
				lo = b < lo ? b : lo;
			}
	f->data = malloc((size_t)w * h * n * sizeof(uint16_t));
	if (!f->data)
		return -ENOMEM;
	for (int y = 0; y < h; y++) {
		const uint16_t *row = src + (size_t)y * w * d->stride;
		uint16_t *out = f->data + (size_t)y * w * n;
		for (int x = 0; x < w; x++)
			for (int c = 0; c < n; c++) {
				unsigned b = site_black(
					d, y, x,
					bayer ? site_colour(d, y, x) : c);
				unsigned v = row[(size_t)x * d->stride + c];
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

static int write_all(int fd, const void *buf, size_t n)
{
	const char *p = buf;
	while (n) {
		ssize_t k = write(fd, p, n);
		if (k < 0 && errno == EINTR)
			continue;
		if (k <= 0)
			return -1;
		p += k;
		n -= (size_t)k;
	}
	return 0;
}

/* 0, or -1 when the writer stopped first (*got: the bytes read). */
static int read_all(int fd, void *buf, size_t n, size_t *got)
{
	char *p = buf;
	*got = 0;
	while (*got < n) {
		ssize_t k = read(fd, p + *got, n - *got);
		if (k < 0 && errno == EINTR)
			continue;
		if (k <= 0)
			return -1;
		*got += (size_t)k;
	}
	return 0;
}

static int decoded_error(struct raw_decoded *d, int code, const char *fmt, ...)
	GLINT_PRINTF(3, 4);

static int decoded_error(struct raw_decoded *d, int code, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(d->msg, sizeof(d->msg), fmt, ap);
	va_end(ap);
	d->ret = -code;
	return d->ret;
}

/* LibRaw's half, in the child: open, check the header's sizes against
 * the file (a bomb is refused before LibRaw allocates), unpack, and fill
 * `d`; *src the visible area's first sample in LibRaw's buffer and *pitch
 * its samples a row. */
static int libraw_decode(libraw_data_t *lr, const char *path,
			 struct raw_decoded *d, const uint16_t **src,
			 size_t *pitch)
{
	struct data_error derr = { 0, 0 };
	int e;

	libraw_set_dataerror_handler(lr, on_data_error, &derr);
	e = libraw_open_file(lr, path);
	if (e != LIBRAW_SUCCESS)
		return decoded_error(d, EINVAL,
				     "%s: not a raw file LibRaw reads (%s): "
				     "expected a camera's raw file or DNG, "
				     "a 16-bit TIFF, or 8-bit photos with "
				     "their exposure times",
				     path, libraw_msg(e));
	const libraw_image_sizes_t *s = &lr->sizes;
	long long bytes = glint_file_size(path);
	/* Sizes from the header, checked before LibRaw unpacks: glint's image
	 * limits, and no more than 64 sites a byte of the file (lossless
	 * raw codecs reach 2 or 3). */
	int ret = glint_image_size_check(
		path, "raw image size", s->raw_width, s->raw_height, bytes,
		(double)s->raw_width * s->raw_height / 64);
	if (ret < 0)
		return decoded_error(d, -ret, "%s", glint_error_msg());
	e = libraw_unpack(lr);
	if (e != LIBRAW_SUCCESS || derr.count) {
		char where[48] = "";
		if (derr.count && derr.offset >= 0)
			snprintf(where, sizeof(where), " at byte %d",
				 derr.offset);
		return decoded_error(d, EIO,
				     "%s: its raw data is truncated or "
				     "corrupt (LibRaw: %s%s)",
				     path,
				     derr.count && derr.offset < 0
					     ? "unexpected end of file"
				     : derr.count ? "bad data"
						  : libraw_msg(e),
				     where);
	}
	const libraw_image_sizes_t *rs = &lr->rawdata.sizes;
	d->raw_width = rs->raw_width;
	d->raw_height = rs->raw_height;
	d->width = rs->width;
	d->height = rs->height;
	d->colors = lr->idata.colors;
	d->filters = lr->idata.filters;
	memcpy(d->cdesc, lr->idata.cdesc, sizeof(d->cdesc) - 1);
	memcpy(d->make, lr->idata.make, sizeof(d->make) - 1);
	memcpy(d->model, lr->idata.model, sizeof(d->model) - 1);
	snprintf(d->unpacker, sizeof(d->unpacker), "%s",
		 libraw_unpack_function_name(lr));
	if (lr->idata.filters)
		for (int y = 0; y < 16; y++)
			for (int x = 0; x < 16; x++)
				d->colour[y][x] =
					(signed char)libraw_COLOR(lr, y, x);
	const libraw_colordata_t *c = &lr->color;
	d->black = c->black;
	d->maximum = c->maximum;
	memcpy(d->cblack, c->cblack, sizeof(d->cblack));
	memcpy(d->pre_mul, c->pre_mul, sizeof(d->pre_mul));
	memcpy(d->rgb_cam, c->rgb_cam, sizeof(d->rgb_cam));
	memcpy(d->cam_xyz, c->cam_xyz, sizeof(d->cam_xyz));
	for (int k = 0; k < 2; k++)
		memcpy(d->dng_matrix[k], c->dng_color[k].colormatrix,
		       sizeof(d->dng_matrix[k]));
	d->iso = lr->other.iso_speed;
	d->shutter = lr->other.shutter;
	if (lr->rawdata.raw_image) {
		d->kind = 1;
		*src = lr->rawdata.raw_image;
	} else if (lr->rawdata.color3_image) {
		d->kind = 3;
		*src = &lr->rawdata.color3_image[0][0];
	} else if (lr->rawdata.color4_image) {
		d->kind = 4;
		*src = &lr->rawdata.color4_image[0][0];
	}
	d->stride = d->kind ? d->kind : 1;
	*pitch = rs->raw_pitch / sizeof(uint16_t);
	if (d->kind &&
	    (!*pitch || d->width < 1 || d->height < 1 ||
	     (size_t)rs->left_margin + d->width > *pitch / (size_t)d->stride ||
	     (size_t)rs->top_margin + d->height > rs->raw_height))
		return decoded_error(d, EINVAL,
				     "%s: LibRaw's visible area (%dx%d at "
				     "%d,%d) lies outside its raw image",
				     path, d->width, d->height, rs->left_margin,
				     rs->top_margin);
	*src += (size_t)rs->top_margin * *pitch +
		(size_t)rs->left_margin * d->stride;
	return 0;
}

/* The child: decode, send the facts and then the visible rows, exit. */
static void libraw_child(const char *path, int fd)
{
	static const int fatal[] = { SIGSEGV, SIGBUS, SIGABRT,
				     SIGFPE,  SIGILL, SIGALRM };
	/* Die by the signal, for the parent to name, rather than in a
	 * handler the parent installed (a fuzzer's, a sanitizer's). */
	for (size_t i = 0; i < sizeof(fatal) / sizeof(fatal[0]); i++)
		signal(fatal[i], SIG_DFL);
	/* A parser caught in a loop is stopped (SIGALRM: an alarm, not a
	 * resource limit, which the rig's unit does not let it set).  A
	 * 50 MP raw unpacks in a few seconds. */
	alarm(300);

	struct raw_decoded *d = calloc(1, sizeof(*d));
	libraw_data_t *lr = libraw_init(0);
	const uint16_t *src = NULL;
	size_t pitch = 0;
	int ok;

	if (!d)
		_exit(3);
	if (!lr)
		decoded_error(d, ENOMEM, "%s: out of memory", path);
	else
		libraw_decode(lr, path, d, &src, &pitch);
	ok = write_all(fd, d, sizeof(*d)) == 0;
	if (ok && d->ret == 0 && d->kind)
		for (int y = 0; ok && y < d->height; y++)
			ok = write_all(fd, src + (size_t)y * pitch,
				       (size_t)d->width * d->stride *
					       sizeof(uint16_t)) == 0;
	_exit(ok ? 0 : 2);
}

/* Why the child ended without sending all it should, as an error. */
static int child_failed(const char *path, pid_t pid)
{
	int status = 0;
	pid_t r;
	while ((r = waitpid(pid, &status, 0)) < 0 && errno == EINTR)
		;
	if (r == pid && WIFSIGNALED(status))
		return glint_error_set(EIO,
				       "%s: LibRaw crashed reading it (%s): "
				       "the file is corrupt or not a raw "
				       "file LibRaw handles safely",
				       path, strsignal(WTERMSIG(status)));
	return glint_error_set(
		EIO,
		"%s: LibRaw's reader stopped before it sent "
		"the image (exit status %d)",
		path, r == pid && WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

/* The child's facts and samples (*src, width x height x stride). */
static int libraw_fork(const char *path, struct raw_decoded *d, uint16_t **src)
{
	int fds[2];
	size_t got;

	*src = NULL;
	if (pipe2(fds, O_CLOEXEC) < 0)
		return glint_error_set(errno, "%s: a pipe for LibRaw: %s", path,
				       strerror(errno));
	fflush(NULL);
	pid_t pid = fork();
	if (pid < 0) {
		int e = errno;
		close(fds[0]);
		close(fds[1]);
		return glint_error_set(e, "%s: fork for LibRaw: %s", path,
				       strerror(e));
	}
	if (pid == 0) {
		close(fds[0]);
		libraw_child(path, fds[1]);
	}
	close(fds[1]);
	int ret = 0;
	if (read_all(fds[0], d, sizeof(*d), &got) < 0) {
		ret = child_failed(path, pid);
		goto out;
	}
	d->msg[sizeof(d->msg) - 1] = 0;
	if (d->ret < 0) {
		ret = glint_error_set(-d->ret > 0 && -d->ret < 4096 ? -d->ret
								    : EIO,
				      "%s", d->msg);
		goto wait;
	}
	if (!d->kind)
		goto wait;
	/* Glint's own check of what it is to allocate: the visible area
	 * within the raw image and glint's limits, at most 4 samples a
	 * pixel, the raw image no larger than the file allows. */
	long long bytes = glint_file_size(path);
	ret = glint_image_size_check(path, "raw image size", d->raw_width,
				     d->raw_height, bytes,
				     (double)d->raw_width * d->raw_height / 64);
	if (ret == 0 &&
	    (d->stride != d->kind || d->width < 1 || d->height < 1 ||
	     d->width > d->raw_width || d->height > d->raw_height))
		ret = glint_error_set(EIO,
				      "%s: LibRaw's reader sent a %dx%d "
				      "image of %d samples a pixel from a "
				      "%dx%d raw image",
				      path, d->width, d->height, d->stride,
				      d->raw_width, d->raw_height);
	if (ret < 0)
		goto wait;
	size_t n = (size_t)d->width * d->height * d->stride;
	*src = malloc(n * sizeof(uint16_t));
	if (!*src) {
		ret = glint_error_set(ENOMEM, "%s: out of memory", path);
		goto wait;
	}
	if (read_all(fds[0], *src, n * sizeof(uint16_t), &got) < 0) {
		free(*src);
		*src = NULL;
		ret = child_failed(path, pid);
		goto out;
	}
wait:
	close(fds[0]);
	fds[0] = -1;
	int status;
	while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
		;
out:
	if (fds[0] >= 0)
		close(fds[0]);
	return ret;
}

static int read_libraw(const char *path, struct glint_frame *f,
		       struct glint_raw_info *info)
{
	struct raw_decoded *d = calloc(1, sizeof(*d));
	uint16_t *src = NULL;
	int ret;

	if (!d)
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	info_init(info, "LibRaw");
	snprintf(info->reader, sizeof(info->reader), "LibRaw %s",
		 libraw_version());
	ret = libraw_fork(path, d, &src);
	if (ret < 0)
		goto out;
	if (d->width < 2 || d->height < 2) {
		ret = glint_error_set(EINVAL, "%s: a %dx%d raw image", path,
				      d->width, d->height);
		goto out;
	}
	d->make[sizeof(d->make) - 1] = d->model[sizeof(d->model) - 1] = 0;
	d->cdesc[sizeof(d->cdesc) - 1] = 0;
	d->unpacker[sizeof(d->unpacker) - 1] = 0;
	snprintf(info->camera, sizeof(info->camera), "%s %s", d->make,
		 d->model);
	const char *layout = NULL;
	int n = 1, bayer = 0;
	if (d->kind == 1 && d->filters) {
		layout = bayer_layout(d);
		bayer = 1;
		if (!layout) {
			ret = glint_error_set(
				EINVAL,
				"%s: a %s mosaic (LibRaw filters 0x%x, colours "
				"%s): glint merges 2 x 2 Bayer (RGGB, GRBG, "
				"GBRG, BGGR), linear RGB and monochrome raw "
				"data",
				path,
				d->filters == 9 ? "Fujifilm X-Trans"
						: "non-Bayer",
				d->filters, d->cdesc);
			goto out;
		}
	} else if (d->kind == 1 && d->colors == 1) {
		layout = "MONO16";
	} else if ((d->kind == 3 || d->kind == 4) && d->colors == 3) {
		layout = "RGB16";
		n = 3;
	} else {
		ret = glint_error_set(EINVAL,
				      "%s: raw data of %d colours that is "
				      "neither a Bayer mosaic, linear RGB nor "
				      "monochrome (%s)",
				      path, d->colors, d->unpacker);
		goto out;
	}
	if (!(d->maximum > 0) || d->maximum > 65535) {
		ret = glint_error_set(EINVAL, "%s: white level %u", path,
				      d->maximum);
		goto out;
	}
	f->width = d->width;
	f->height = d->height;
	f->channels = n;
	snprintf(f->format, sizeof(f->format), "%s", layout);
	snprintf(f->source_format, sizeof(f->source_format), "LibRaw");
	f->linear = 1;
	f->white_level = d->maximum;
	f->bit_depth = 1;
	while (f->bit_depth < 16 && (1u << f->bit_depth) - 1 < d->maximum)
		f->bit_depth++;
	if (copy_visible(d, src, n, bayer, f) < 0) {
		ret = glint_error_set(ENOMEM, "%s: out of memory", path);
		goto out;
	}
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
	if (d->iso > 0 && isfinite(d->iso)) {
		info->iso = d->iso;
		f->gain = info->iso / 100;
	}
	if (d->shutter > 0 && isfinite(d->shutter)) {
		f->exposure_s = d->shutter;
		info->has_exposure = 1;
	}
	colour_matrix(d, info);
out:
	if (ret < 0)
		glint_frame_release(f);
	free(src);
	free(d);
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
