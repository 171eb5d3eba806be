/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_EXR_CXX_H
#define GLINT_CORE_EXR_CXX_H

/*
 * Fallback EXR reader on OpenEXR's C++ library, for compressions the C core
 * of OpenEXR 3.1 cannot decode (DWAA, DWAB).  Same contract as
 * glint_exr_read(); never throws.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected; never throws.  Threads: re-entrant.  Who frees:
 * the image out with glint_image_free().
 */

#include "image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The C++ library's reader for what OpenEXRCore cannot decode (DWAA,
 * DWAB); *out as glint_exr_read(). */
int glint_exr_read_cxx(const char *path, struct glint_image **out);

#ifdef __cplusplus
}
#endif

#endif
