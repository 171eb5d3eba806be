/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_EXR_WINDOWS_H
#define GLINT_TESTS_EXR_WINDOWS_H

/* An EXR file's data and display windows as OpenEXR itself reads them. */

#include <OpenEXR/openexr.h>
#include <string.h>

/* 0, or -1 when the file's header cannot be read. */
static inline int test_exr_windows(const char *path, exr_attr_box2i_t *dw,
				   exr_attr_box2i_t *disp)
{
	exr_context_t ctx = NULL;
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	int ok;

	memset(dw, 0, sizeof(*dw));
	memset(disp, 0, sizeof(*disp));
	ok = exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS &&
	     exr_get_data_window(ctx, 0, dw) == EXR_ERR_SUCCESS &&
	     exr_get_display_window(ctx, 0, disp) == EXR_ERR_SUCCESS;
	if (ctx)
		exr_finish(&ctx);
	return ok ? 0 : -1;
}

#endif
