/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_EXR_INTERNAL_H
#define GLINT_CORE_EXR_INTERNAL_H

/*
 * Shared by exr.c (the reader and writer) and exr_check.c; private to
 * core/.
 */

/* 0 when every attribute of the EXR header at path fits in the file and
 * is the size its type reads (exr_check.c says why); else a negative
 * errno with glint_error_msg() naming the file and the attribute. */
int glint_exr_check_attribute_sizes(const char *path);

#endif
