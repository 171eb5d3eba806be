/* SPDX-License-Identifier: MIT */
/* One overwrite rule for every output file (output.h). */
#define _POSIX_C_SOURCE 200809L /* lstat */
#include "output.h"

#include "error.h"
#include "formats.h"
#include "json.h"
#include "path.h"
#include "tiff.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <tiffio.h>
#include <unistd.h>

static int is_software(const char *s)
{
	size_t n = strlen(GLINT_OUTPUT_SOFTWARE);
	return !strncmp(s, GLINT_OUTPUT_SOFTWARE, n) &&
	       (s[n] == 0 || s[n] == ' ');
}

static int tiff_is_glints(const char *path)
{
	struct glint_tiff_msgs m;
	TIFF *tif = glint_tiff_open(path, "r", &m);
	const char *s = NULL;
	int own = tif && TIFFGetField(tif, TIFFTAG_SOFTWARE, &s) == 1 && s &&
		  is_software(s);
	if (tif)
		TIFFClose(tif);
	return own;
}

/* A JSON document glint wrote: its "glint" key (sessions, runs, hdr and
 * probe reports) or a generator naming it (a glTF export's asset). */
static int json_is_glints(const char *path)
{
	json_t *doc = glint_json_read_quiet(path);
	json_t *asset = json_object_get(doc, "asset");
	const char *g = json_string_value(json_object_get(doc, "generator"));
	if (!g)
		g = json_string_value(json_object_get(asset, "generator"));
	int own = json_object_get(doc, "glint") || (g && is_software(g));
	json_decref(doc);
	return own;
}

int glint_output_is_glints(const char *path, const char **why)
{
	char head[512], sw[256];
	const char *w = "no record of glint as its writer";
	int own = 0;
	long long size;
	int fd = glint_open_regular(path, &size);
	if (fd < 0) {
		if (why)
			*why = "not a regular file glint can read";
		return 0;
	}
	ssize_t got = read(fd, head, sizeof(head) - 1);
	close(fd);
	if (got < 0)
		got = 0;
	head[got] = 0;
	if (got >= 4 && !memcmp(head, "\x76\x2f\x31\x01", 4)) {
		own = glint_exr_software(path, sw, sizeof(sw)) == 0 &&
		      is_software(sw);
		w = "an OpenEXR file without glint as its \"software\"";
	} else if (got >= 8 && !memcmp(head, "\x89PNG\r\n\x1a\n", 8)) {
		own = glint_png_software(path, sw, sizeof(sw)) == 0 &&
		      is_software(sw);
		w = "a PNG without glint as its \"Software\"";
	} else if (got >= 4 &&
		   (!memcmp(head, "II*\0", 4) || !memcmp(head, "MM\0*", 4))) {
		own = tiff_is_glints(path);
		w = "a TIFF without glint as its Software";
	} else if (got >= 2 && head[0] == 'P' &&
		   (head[1] == 'F' || head[1] == 'f')) {
		w = "a PFM holds no record of its writer";
	} else if (got >= 2 && head[0] == '#' && head[1] == '?') {
		/* Radiance: glint's header line before the blank line. */
		char *end = strstr(head, "\n\n");
		char *line = strstr(head, "\n# written by glint\n");
		own = line && (!end || line < end);
		w = "a Radiance file without glint's header line";
	} else {
		/* Text: a JSON document, or an export's heading. */
		const char *s = head + strspn(head, " \t\r\n");
		if (*s == '{')
			own = json_is_glints(path);
		else
			own = strstr(head, "glint export of ") != NULL ||
			      !strncmp(head, "# written by glint", 18);
		w = "no record of glint as its writer";
	}
	if (why)
		*why = own ? "glint's" : w;
	return own;
}

int glint_output_check(const char *path, int force, const char *const *inputs)
{
	struct stat st, in;
	if (lstat(path, &st) < 0)
		return errno == ENOENT ? 0
				       : glint_error_set(errno, "%s: %s", path,
							 strerror(errno));
	if (!force)
		return glint_error_set(EEXIST,
				       "%s exists: refusing to replace it "
				       "(--force replaces a file glint wrote)",
				       path);
	if (!S_ISREG(st.st_mode))
		return glint_error_set(EEXIST,
				       "%s is %s, not a file glint wrote: "
				       "refusing to replace it even with "
				       "--force",
				       path,
				       S_ISLNK(st.st_mode) ? "a symbolic link"
				       : S_ISDIR(st.st_mode)
					       ? "a folder"
					       : "a special file");
	for (int k = 0; inputs && inputs[k]; k++)
		if (stat(inputs[k], &in) == 0 && in.st_dev == st.st_dev &&
		    in.st_ino == st.st_ino)
			return glint_error_set(EEXIST,
					       "%s is an input of this command "
					       "(%s): refusing to replace it "
					       "even with --force",
					       path, inputs[k]);
	const char *why;
	if (!glint_output_is_glints(path, &why))
		return glint_error_set(EEXIST,
				       "%s: %s, so not known to be glint's "
				       "output: refusing to replace it even "
				       "with --force (move it away or write "
				       "elsewhere)",
				       path, why);
	return 0;
}
