/* SPDX-License-Identifier: MIT */
/*
 * JPEG photos through libjpeg-turbo: 8-bit RGB code values as the camera
 * stored them.  Every error and every warning (libjpeg's "corrupt data"
 * warnings fill what it could not decode with grey and go on) is an error
 * naming the file: a photo glint measures is decoded whole or not at all.
 */
#include "error.h"
#include "formats.h"
#include "image.h"
#include "path.h"

#include <jpeglib.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct jpeg_err {
	struct jpeg_error_mgr mgr;
	jmp_buf jump;
	char msg[JMSG_LENGTH_MAX];
};

static void jpeg_fail(j_common_ptr cinfo)
{
	struct jpeg_err *e = (struct jpeg_err *)cinfo->err;

	(*cinfo->err->format_message)(cinfo, e->msg);
	longjmp(e->jump, 1);
}

/* level -1 is a warning about the data (corrupt, truncated): an error
 * here; trace messages (level >= 0) are dropped. */
static void jpeg_message(j_common_ptr cinfo, int level)
{
	if (level < 0)
		jpeg_fail(cinfo);
}

int glint_jpeg_read_rgb8(const char *path, int *w, int *h, uint8_t **px)
{
	struct jpeg_decompress_struct cinfo;
	struct jpeg_err err;
	uint8_t *volatile out = NULL;
	FILE *volatile fp;
	long long size = 0;

	*px = NULL;
	int fd = glint_open_regular(path, &size);
	if (fd < 0)
		return fd;
	fp = fdopen(fd, "rb");
	if (!fp) {
		close(fd);
		return glint_error_set(errno, "%s: %s", path, strerror(errno));
	}
	cinfo.err = jpeg_std_error(&err.mgr);
	err.mgr.error_exit = jpeg_fail;
	err.mgr.emit_message = jpeg_message;
	if (setjmp(err.jump)) {
		jpeg_destroy_decompress(&cinfo);
		fclose(fp);
		free(out);
		return glint_error_set(EIO, "%s: not a readable JPEG: %s", path,
				       err.msg);
	}
	jpeg_create_decompress(&cinfo);
	jpeg_stdio_src(&cinfo, fp);
	jpeg_read_header(&cinfo, TRUE);
	/* Each 8 × 8 block takes at least a bit of a baseline scan; a
	 * progressive scan's end-of-band runs pack more, and a photo is not
	 * a flat field: 1032 pixels a byte, as the other 8-bit readers. */
	int ret = glint_image_size_check(
		path, "SOF", cinfo.image_width, cinfo.image_height, size,
		(double)cinfo.image_width * cinfo.image_height / 1032);
	if (ret < 0) {
		jpeg_destroy_decompress(&cinfo);
		fclose(fp);
		return ret;
	}
	cinfo.out_color_space = JCS_RGB;
	jpeg_start_decompress(&cinfo);
	if (cinfo.output_components != 3) {
		snprintf(err.msg, sizeof(err.msg),
			 "%d output components, not 3",
			 cinfo.output_components);
		longjmp(err.jump, 1);
	}
	size_t stride = (size_t)cinfo.output_width * 3;
	out = malloc(stride * cinfo.output_height);
	if (!out) {
		jpeg_destroy_decompress(&cinfo);
		fclose(fp);
		return glint_error_set(ENOMEM, "%s: out of memory", path);
	}
	while (cinfo.output_scanline < cinfo.output_height) {
		JSAMPROW row = out + stride * cinfo.output_scanline;
		jpeg_read_scanlines(&cinfo, &row, 1);
	}
	jpeg_finish_decompress(&cinfo);
	*w = (int)cinfo.output_width;
	*h = (int)cinfo.output_height;
	jpeg_destroy_decompress(&cinfo);
	fclose(fp);
	*px = out;
	return 0;
}
