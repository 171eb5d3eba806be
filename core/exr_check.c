/* SPDX-License-Identifier: MIT */
/*
 * An EXR header's attribute sizes against the file, before OpenEXR's C++
 * library reads it (exr_internal.h).
 */
#include "exr_internal.h"

#include "error.h"
#include "path.h"
#include "image.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The bytes of the value of an attribute of type `type` that the C++
 * library reads regardless of the size the header states: -1 for the
 * types whose value it reads by that size (string, floatvector, opaque
 * ones), 0 for the ones whose length is in the value itself. */
static int imf_fixed_bytes(const char *type)
{
	static const struct {
		const char *type;
		int bytes;
	} t[] = {
		{ "box2i", 16 },
		{ "box2f", 16 },
		{ "compression", 1 },
		{ "double", 8 },
		{ "envmap", 1 },
		{ "float", 4 },
		{ "int", 4 },
		{ "keycode", 28 },
		{ "lineOrder", 1 },
		{ "m33f", 36 },
		{ "m33d", 72 },
		{ "m44f", 64 },
		{ "m44d", 128 },
		{ "rational", 8 },
		{ "tiledesc", 9 },
		{ "timecode", 8 },
		{ "v2i", 8 },
		{ "v2f", 8 },
		{ "v2d", 16 },
		{ "v3i", 12 },
		{ "v3f", 12 },
		{ "v3d", 24 },
		{ "chromaticities", 32 },
		{ "deepImageState", 1 },
		{ "chlist", 0 },
		{ "preview", 0 },
		{ "stringvector", 0 },
	};
	for (size_t k = 0; k < sizeof(t) / sizeof(t[0]); k++)
		if (!strcmp(type, t[k].type))
			return t[k].bytes;
	return -1;
}

/* The length of a value the C++ library parses by its content (a
 * channel list, a preview image, a string vector), from its len bytes
 * v: what the library would read, or -1 when it would run past len. */
static long long imf_parsed_bytes(const char *type, const uint8_t *v,
				  size_t len)
{
	size_t at = 0;

	if (!strcmp(type, "chlist")) {
		for (;;) { /* name, type, linear + 3, x and y sampling */
			const uint8_t *z =
				at < len ? memchr(v + at, 0, len - at) : NULL;
			if (!z)
				return -1;
			if (z == v + at)
				return (long long)at + 1;
			at = (size_t)(z - v) + 1 + 16;
			if (at > len)
				return -1;
		}
	}
	if (!strcmp(type, "preview")) { /* width, height, RGBA8 pixels */
		uint32_t w, h;
		if (len < 8)
			return -1;
		memcpy(&w, v, 4);
		memcpy(&h, v + 4, 4);
		uint64_t px = (uint64_t)w * h; /* below 2^64: no overflow */
		if (px > (len - 8) / 4)	       /* more than the value holds */
			return -1;
		return 8 + 4 * (long long)px;
	}
	while (at < len) { /* stringvector: length, bytes */
		int32_t n;
		if (len - at < 4)
			return -1;
		memcpy(&n, v + at, 4);
		if (n < 0 || (size_t)n > len - at - 4)
			return -1;
		at += 4 + (size_t)n;
	}
	return (long long)at;
}

/*
 * Before the C++ library reads a header: each attribute (name, type,
 * 32-bit size, value) must fit in the file, and where the library reads
 * a value by its type rather than by the size the header states, the
 * two must agree, or it would read on out of step with the sizes.  Imf
 * allocates what an opaque attribute's size says (fuzz_exr: a 704-byte
 * file's "type" string asked for 1.7 GB; a 756-byte file whose channel
 * list was shorter than its size led Imf to an opaque attribute of 1.6
 * GB that this check, stepping by the size, never saw).  Single- and
 * multi-part headers; a name is at most 255 bytes.
 */
int glint_exr_check_attribute_sizes(const char *path)
{
	enum { MAX_PARSED = 1 << 20 };
	long long size = glint_file_size(path);
	uint8_t buf[600], *val = NULL;
	FILE *fp = glint_fopen_regular(path, "rb");
	long long pos = 8;
	int ret = 0, headers = 0;

	if (!fp)
		return -errno;
	while (ret == 0 && headers < 1024) {
		if (fseek(fp, (long)pos, SEEK_SET) < 0)
			break;
		size_t n = fread(buf, 1, sizeof(buf), fp);
		if (n == 0)
			break;
		if (buf[0] == 0) { /* end of a header (two: of all) */
			if (++headers > 1 || n < 2 || buf[1] == 0)
				break;
			pos++;
			continue;
		}
		const uint8_t *name_end = memchr(buf, 0, n < 256 ? n : 256);
		const uint8_t *type_end =
			name_end ? memchr(name_end + 1, 0,
					  (size_t)(buf + n - name_end - 1))
				 : NULL;
		if (!type_end || type_end + 5 > buf + n)
			break; /* the C core said what is wrong, if anything */
		const char *type = (const char *)name_end + 1;
		int32_t len;
		memcpy(&len, type_end + 1, 4);
		long long at = pos + (type_end + 5 - buf);
		if (len < 0 || at + len > size) {
			ret = glint_error_set(EINVAL,
					      "%s: header attribute '%.64s' "
					      "says %d bytes at byte %lld, but "
					      "the file holds %lld",
					      path, (const char *)buf, len, at,
					      size);
			break;
		}
		int fixed = imf_fixed_bytes(type);
		long long reads = fixed > 0 ? fixed : len;
		/* a preview's size is in its first 8 bytes */
		size_t want = !strcmp(type, "preview")
				      ? (size_t)(len < 8 ? len : 8)
				      : (size_t)len;
		if (fixed == 0 && want > MAX_PARSED) {
			reads = -1;
		} else if (fixed == 0) {
			uint8_t *v = realloc(val, want > 0 ? want : 1);
			if (!v) {
				ret = glint_error_set(ENOMEM, "out of memory");
				break;
			}
			val = v;
			if (fseek(fp, (long)at, SEEK_SET) < 0 ||
			    fread(val, 1, want, fp) != want) {
				ret = glint_error_set(EIO,
						      "%s: cannot read the "
						      "header at byte %lld",
						      path, at);
				break;
			}
			reads = imf_parsed_bytes(type, val, (size_t)len);
		}
		if (reads != len) {
			char took[64];
			if (reads < 0)
				snprintf(took, sizeof(took),
					 "is not a %.32s of that size", type);
			else
				snprintf(took, sizeof(took), "takes %lld",
					 reads);
			ret = glint_error_set(EINVAL,
					      "%s: header attribute '%.64s' "
					      "of type %.32s says %d bytes at "
					      "byte %lld, but its value %s",
					      path, (const char *)buf, type,
					      len, at, took);
			break;
		}
		pos = at + len;
	}
	free(val);
	fclose(fp);
	return ret;
}
