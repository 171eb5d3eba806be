/* SPDX-License-Identifier: MIT */
/*
 * Capture files: raw frames round-trip bit for bit through their 16-bit
 * PNG with metadata; truncated or foreign files fail naming the file; a
 * session directory says "incomplete" until finished, and lists exactly
 * the frames on disk.
 */
#include "test.h"

#include "capture/hdr/frame_file.h"
#include "capture/run.h"
#include "capture/hdr/session.h"
#include "core/error.h"
#include "core/image.h"
#include "core/json.h"
#include "core/log.h"

#include <fcntl.h>
#include <math.h>
#include <unistd.h>

#include <jansson.h>
#include <stdint.h>
#include <sys/stat.h>

static struct glint_frame make_frame(int w, int h, int ch, int bits)
{
	struct glint_frame f;
	memset(&f, 0, sizeof(f));
	f.width = w;
	f.height = h;
	f.channels = ch;
	f.bit_depth = bits;
	f.linear = ch == 1;
	snprintf(f.format, sizeof(f.format), ch == 1 ? "GRBG16" : "RGB16");
	snprintf(f.source_format, sizeof(f.source_format), "SGRBG12P");
	f.exposure_s = 0.0123;
	f.gain = 2.5;
	f.black_level = 64;
	f.sequence = 77;
	f.data = malloc((size_t)w * h * ch * sizeof(uint16_t));
	uint32_t x = 12345;
	for (int i = 0; i < w * h * ch; i++) {
		x = x * 1664525u + 1013904223u;
		f.data[i] = (uint16_t)((x >> 8) & ((1u << bits) - 1));
	}
	return f;
}

static void roundtrip(int ch, int bits, const char *ext, const char *dir)
{
	char path[512];
	struct glint_frame f = make_frame(37, 23, ch, bits), g;
	snprintf(path, sizeof(path), "%s/f%d%s", dir, ch, ext);
	char *meta = glint_frame_metadata_json(&f, 3);
	CHECK(glint_frame_write(path, &f, meta) == 0, "%s", glint_error_msg());
	free(meta);
	CHECK(glint_frame_read(path, &g, NULL) == 0, "%s", glint_error_msg());
	if (g.data) {
		CHECK(g.width == 37 && g.height == 23 && g.channels == ch,
		      "%dx%dx%d", g.width, g.height, g.channels);
		CHECK(!memcmp(f.data, g.data, (size_t)37 * 23 * ch * 2),
		      "pixel data changed on the way");
		CHECK(g.exposure_s == f.exposure_s && g.gain == f.gain &&
			      g.black_level == 64 && g.bit_depth == bits &&
			      g.sequence == 77 && !strcmp(g.format, f.format),
		      "metadata: %g s x%g black %g bits %d seq %llu %s",
		      g.exposure_s, g.gain, g.black_level, g.bit_depth,
		      (unsigned long long)g.sequence, g.format);
	}
	glint_frame_release(&f);
	glint_frame_release(&g);
}

static void half(const char *dir, const char *ext);

static void test_frames(const char *dir)
{
	/* DNG, as sessions write them, and PNG, as older ones did. */
	for (int k = 0; k < 2; k++) {
		const char *ext = k ? ".png" : ".dng";
		roundtrip(1, 12, ext, dir);
		roundtrip(3, 8, ext, dir);
		roundtrip(1, 16, ext, dir);
		half(dir, ext);
	}
	/* Not a PNG. */
	char dst[512];
	struct glint_frame g;
	snprintf(dst, sizeof(dst), "%s/text.png", dir);
	FILE *out = fopen(dst, "wb");
	fputs("hello\n", out);
	fclose(out);
	CHECK(glint_frame_read(dst, &g, NULL) < 0, "a text file was read");
	CHECK_MSG(glint_error_msg(), "text.png");
	/* A TIFF that is not a glint frame: an 8-bit greyscale one. */
	snprintf(dst, sizeof(dst), "%s/grey.dng", dir);
	out = fopen(dst, "wb");
	static const unsigned char tiff[] = {
		'I', 'I', 42, 0, 8, 0, 0, 0,		 /* header, IFD at 8 */
		4,   0,					 /* 4 entries */
		0,   1,	  3,  0, 1, 0, 0, 0, 1, 0, 0, 0, /* width 1 */
		1,   1,	  3,  0, 1, 0, 0, 0, 1, 0, 0, 0, /* height 1 */
		2,   1,	  3,  0, 1, 0, 0, 0, 8, 0, 0, 0, /* 8 bits */
		17,  1,	  4,  0, 1, 0, 0, 0, 0, 0, 0, 0, /* strip at 0 */
		0,   0,	  0,  0
	};
	fwrite(tiff, 1, sizeof(tiff), out);
	fclose(out);
	CHECK(glint_frame_read(dst, &g, NULL) < 0 && g.data == NULL,
	      "an 8-bit TIFF was read as a frame");
	CHECK_MSG(glint_error_msg(), "grey.dng");
	CHECK_MSG(glint_error_msg(), "expected a 16-bit");
}

/* A frame file cut to half its length is refused, naming it. */
static void half(const char *dir, const char *ext)
{
	char src[512], dst[512];
	struct glint_frame g;
	snprintf(src, sizeof(src), "%s/f1%s", dir, ext);
	snprintf(dst, sizeof(dst), "%s/half%s", dir, ext);
	FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
	fseek(in, 0, SEEK_END);
	long n = ftell(in);
	fseek(in, 0, SEEK_SET);
	char *buf = malloc((size_t)n);
	CHECK(fread(buf, 1, (size_t)n, in) == (size_t)n, "read %s", src);
	fwrite(buf, 1, (size_t)n / 2, out);
	fclose(in);
	fclose(out);
	CHECK(glint_frame_read(dst, &g, NULL) < 0 && g.data == NULL,
	      "a truncated frame was read");
	CHECK_MSG(glint_error_msg(), "half");
	free(buf);
}

static json_t *load(const char *dir, const char *name)
{
	char path[4200];
	json_error_t e;
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	return json_load_file(path, 0, &e);
}

static void test_session(const char *dir)
{
	struct glint_camera_info in;
	struct glint_session *s;
	struct glint_frame f = make_frame(16, 8, 1, 12);
	char root[512], sdir[4096];

	memset(&in, 0, sizeof(in));
	snprintf(in.backend, sizeof(in.backend), "sim");
	snprintf(in.name, sizeof(in.name), "test");
	snprintf(root, sizeof(root), "%s/sessions", dir);
	CHECK(glint_session_create(root, "probe", "{\"camera\": {}}\n", &in,
				   &s) == 0,
	      "%s", glint_error_msg());
	if (!s)
		return;
	snprintf(sdir, sizeof(sdir), "%s", glint_session_dir(s));
	json_t *doc = load(sdir, "session.json");
	CHECK(doc && !strcmp(json_string_value(json_object_get(doc, "status")),
			     "incomplete"),
	      "a new session is not marked incomplete");
	json_decref(doc);
	CHECK(glint_session_add_frame(s, &f, 0) == 0, "%s", glint_error_msg());
	f.exposure_s *= 2;
	CHECK(glint_session_add_frame(s, &f, 1) == 0, "%s", glint_error_msg());
	doc = load(sdir, "session.json");
	CHECK(doc && json_array_size(json_object_get(doc, "frames")) == 2,
	      "session.json lists %zu frames after 2",
	      doc ? json_array_size(json_object_get(doc, "frames")) : 0);
	json_decref(doc);
	/* Stopped by an error: stays incomplete, says why, keeps frames. */
	struct glint_bracket b;
	memset(&b, 0, sizeof(b));
	CHECK(glint_session_finish(s, &b, "bracket", "camera disappeared",
				   NULL) == 0,
	      "%s", glint_error_msg());
	doc = load(sdir, "session.json");
	CHECK(doc &&
		      !strcmp(json_string_value(json_object_get(doc, "status")),
			      "incomplete") &&
		      !strcmp(json_string_value(json_object_get(doc, "error")),
			      "camera disappeared"),
	      "an interrupted session must stay incomplete with its error");
	json_decref(doc);
	struct glint_frame g;
	char p[4200];
	snprintf(p, sizeof(p), "%s/frame-001.dng", sdir);
	CHECK(glint_frame_read(p, &g, NULL) == 0 &&
		      g.exposure_s == f.exposure_s,
	      "frame 1 not kept: %s", glint_error_msg());
	glint_frame_release(&g);
	glint_frame_release(&f);
}

/* run.json: written whole, read back; names outside the run refused. */
static void test_run(const char *dir)
{
	static struct glint_run_samples rs, back;
	char run[512], path[700];
	snprintf(run, sizeof(run), "%s/run-1", dir);
	CHECK(mkdir(run, 0777) == 0, "mkdir %s", run);
	CHECK(glint_run_read(run, &back) == 0, "a folder without run.json "
					       "is not a run");
	rs.n = 2;
	snprintf(rs.session[0], sizeof(rs.session[0]), "%s/sample-a", run);
	snprintf(rs.session[1], sizeof(rs.session[1]), "%s/sample-b", run);
	rs.light[0] = 1;
	rs.light[1] = 2;
	CHECK(glint_run_write(run, &rs) == 0, "%s", glint_error_msg());
	CHECK(glint_run_read(run, &back) == 1 && back.n == 2 &&
		      !strcmp(back.session[1], rs.session[1]) &&
		      back.light[1] == 2,
	      "read back: %s", glint_error_msg());
	snprintf(path, sizeof(path), "%s/fit", run);
	CHECK(!strcmp(back.out, path), "out %s", back.out);
	static const char *const bad[] = {
		"{\"samples\": [{\"session\": \"../x\"}]}",
		"{\"samples\": [{\"session\": \"..\"}]}",
		"{\"samples\": [{\"session\": \"\"}]}",
		"{\"samples\": [{\"session\": \"a\", \"light\": \"1\"}]}",
		"{\"samples\": []}",
		"{\"samples\": [",
	};
	snprintf(path, sizeof(path), "%s/run.json", run);
	for (size_t i = 0; i < sizeof(bad) / sizeof(*bad); i++) {
		FILE *f = fopen(path, "w");
		CHECK(f && fputs(bad[i], f) >= 0, "write %s", path);
		if (f)
			fclose(f);
		CHECK(glint_run_read(run, &back) < 0 &&
			      strstr(glint_error_msg(), "run.json"),
		      "%s: accepted (%s)", bad[i], glint_error_msg());
	}
}

/*
 * Special files where a reader expects a file: a FIFO (whose open would
 * wait for a writer forever) as a document, an image or a camera frame,
 * a folder; each refused at once, naming the
 * file and what it is.  A document over the cap is refused by size, read
 * or not.  (Were the FIFO opened blocking, the test would hang and meet
 * its timeout.)
 */
static void test_special_files(const char *dir)
{
	static const char *const names[] = { "fifo.json", "fifo.exr",
					     "fifo.png",  "fifo.hdr",
					     "fifo.pfm",  "frame-fifo.png" };
	char path[512];
	json_t *doc = NULL;
	struct glint_image *img = NULL;
	struct glint_frame frame;
	int index;

	for (int i = 0; i < 6; i++) {
		snprintf(path, sizeof(path), "%s/%s", dir, names[i]);
		CHECK(mkfifo(path, 0600) == 0, "mkfifo %s", path);
		int ret = i == 0   ? glint_json_load(path, &doc)
			  : i == 5 ? glint_frame_read(path, &frame, &index)
				   : glint_image_read(path, &img);
		CHECK(ret < 0 && strstr(glint_error_msg(), path) &&
			      strstr(glint_error_msg(), "a FIFO"),
		      "%s: '%s'", names[i], glint_error_msg());
		glint_error_clear();
	}
	snprintf(path, sizeof(path), "%s/folder.json", dir);
	CHECK(mkdir(path, 0700) == 0, "mkdir");
	CHECK(glint_json_load(path, &doc) < 0 &&
		      strstr(glint_error_msg(), "a folder"),
	      "'%s'", glint_error_msg());
	glint_error_clear();
	/* over the cap by its size (sparse: no 16 MiB written) */
	snprintf(path, sizeof(path), "%s/huge.json", dir);
	int fd = open(path, O_CREAT | O_WRONLY, 0600);
	CHECK(fd >= 0 && ftruncate(fd, GLINT_JSON_MAX_BYTES + 1) == 0,
	      "ftruncate");
	if (fd >= 0)
		close(fd);
	CHECK(glint_json_load(path, &doc) < 0 &&
		      strstr(glint_error_msg(), "at most"),
	      "'%s'", glint_error_msg());
	glint_error_clear();
	/* and while read, past the cap given */
	snprintf(path, sizeof(path), "%s/job.json", dir);
	FILE *f = fopen(path, "w");
	if (f) {
		fprintf(f, "{\"kind\": \"fit\", \"pad\": \"%0100d\"}\n", 0);
		fclose(f);
	}
	fd = open(path, O_RDONLY);
	CHECK(fd >= 0 && glint_json_load_fd(fd, "job.json", 64, &doc) < 0 &&
		      strstr(glint_error_msg(), "job.json"),
	      "'%s'", glint_error_msg());
	glint_error_clear();
	if (fd >= 0)
		close(fd);
	CHECK(glint_json_load(path, &doc) == 0 && doc, "%s", glint_error_msg());
	json_decref(doc);
}

/* Text from another user's file shown safely: controls and broken UTF-8
 * escaped, printable text and valid UTF-8 kept. */
/* The merge's negative-site limit keeps its false alarms to one photo
 * in 10,000 at every size: n sites times the normal tail beyond the
 * limit, and a 12 MP merge allowed deeper than the 5 sigma of a small
 * one (where -5 sigma happens three times by chance). */
static void test_negative_limit(void)
{
	static const double sizes[] = { 1e2, 7.7e4, 3.1e6, 1.23e7, 5e7 };
	double last = 0;
	for (int k = 0; k < 5; k++) {
		double t = glint_negative_sigma_limit((size_t)sizes[k]);
		double alarms = sizes[k] * 0.5 * erfc(t / sqrt(2));
		CHECK(t >= 5 && t >= last &&
			      (t == 5 || fabs(alarms / 1e-4 - 1) < 1e-3),
		      "%g sites: limit %.3f sigma, %.3g false alarms a photo",
		      sizes[k], t, alarms);
		last = t;
	}
	CHECK(glint_negative_sigma_limit(12330000) > 6.5, "12 MP: limit %.2f",
	      glint_negative_sigma_limit(12330000));
	CHECK(glint_negative_sigma_limit(100) == 5, "100 sites: %.2f",
	      glint_negative_sigma_limit(100));
}

static void test_printable(void)
{
	char out[64];
	CHECK(!strcmp(glint_text_printable("job-1 caf\xc3\xa9 \xe2\x82\xac",
					   out, sizeof(out)),
		      "job-1 caf\xc3\xa9 \xe2\x82\xac"),
	      "plain text and UTF-8 changed: %s", out);
	CHECK(!strcmp(glint_text_printable("a\x1b]0;owned\x07"
					   "b\x7f",
					   out, sizeof(out)),
		      "a\\x1b]0;owned\\x07b\\x7f"),
	      "C0/DEL not escaped: %s", out);
	CHECK(!strcmp(glint_text_printable("\xc2\x9b"
					   "31m \x9b \xff \xed\xa0\x80",
					   out, sizeof(out)),
		      "\\xc2\\x9b31m \\x9b \\xff \\xed\\xa0\\x80"),
	      "C1, stray or surrogate bytes not escaped: %s", out);
	/* cut at a whole escape, always terminated */
	glint_text_printable("\x1b\x1b\x1b", out, 9);
	CHECK(!strcmp(out, "\\x1b\\x1b"), "truncation: %s", out);
}

int main(void)
{
	char dir[] = "/tmp/glint-capture-files-XXXXXX";
	if (!mkdtemp(dir))
		return 1;
	RUN_ARG(test_frames, dir);
	RUN_ARG(test_session, dir);
	RUN_ARG(test_run, dir);
	RUN_ARG(test_special_files, dir);
	RUN(test_printable);
	RUN(test_negative_limit);
	test_remove_dir(dir);
	return test_result();
}
