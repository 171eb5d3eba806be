/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "capture/hdr/session.h"

#include "capture/hdr/frame_file.h"

#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/lockfile.h"
#include "core/log.h"
#include "core/error.h"
#include "core/json.h"
#include "core/path.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

struct glint_session {
	char dir[GLINT_PATH_MAX]; /* ROOT/KIND-STAMP[-N], room for its files */
	json_t *doc;
	FILE *log;
};

static void utc_stamp(char *buf, size_t n, int compact)
{
	struct timespec ts;
	struct tm tm;
	clock_gettime(CLOCK_REALTIME, &ts);
	gmtime_r(&ts.tv_sec, &tm);
	strftime(buf, n, compact ? "%Y%m%dT%H%M%SZ" : "%Y-%m-%dT%H:%M:%SZ",
		 &tm);
}

static int fsync_path(const char *path)
{
	int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (fd < 0)
		return glint_error_set(errno, "%s: %s", path, strerror(errno));
	int r = fsync(fd);
	int e = errno;
	close(fd);
	return r < 0 && e != EINVAL
		       ? glint_error_set(e, "%s: fsync: %s", path, strerror(e))
		       : 0;
}

static int save_doc(struct glint_session *s)
{
	char path[GLINT_PATH_MAX];
	char *text =
		json_dumps(s->doc, JSON_INDENT(2) | JSON_REAL_PRECISION(17));
	if (!text)
		return glint_error_set(ENOMEM, "out of memory");
	int ret = glint_path_join(path, sizeof(path), s->dir, "session.json");
	if (ret < 0) {
		free(text);
		return ret;
	}
	size_t n = strlen(text);
	text[n] = '\n';
	ret = glint_atomic_write_file(path, text, n + 1);
	free(text);
	return ret;
}

static json_t *camera_json(const struct glint_camera_info *in)
{
	json_t *fmts = json_array();
	for (int i = 0; i < in->nformats; i++)
		json_array_append_new(fmts, json_string(in->formats[i]));
	return json_pack(
		"{s:s, s:s, s:s, s:i, s:i, s:o, s:i, s:b, s:[f, f], "
		"s:f, s:[f, f], s:s, s:s, s:f}",
		"backend", in->backend, "name", in->name, "detail", in->detail,
		"width", in->width, "height", in->height, "formats", fmts,
		"bit_depth", in->bit_depth, "manual_exposure",
		in->manual_exposure, "exposure_range_s", in->exposure_min_s,
		in->exposure_max_s, "exposure_step_s", in->exposure_step_s,
		"gain_range", in->gain_min, in->gain_max, "exposure_control",
		in->exposure_control, "gain_control", in->gain_control,
		"frame_period_min_s", in->frame_period_min_s);
}

int glint_session_create(const char *root, const char *kind,
			 const char *rig_json,
			 const struct glint_camera_info *cam,
			 struct glint_session **out)
{
	struct glint_session *s;
	char stamp[32], path[GLINT_PATH_MAX];
	int ret;

	*out = NULL;
	/* Room for "/probe-YYYYmmddTHHMMSSZ-999/frame-000.json": every
	 * path in the session then fits whole. */
	if (strlen(root) + 64 >= GLINT_PATH_MAX)
		return glint_error_set(ENAMETOOLONG,
				       "capture root %.64s...: longer than %d "
				       "bytes",
				       root, GLINT_PATH_MAX - 64);
	if (mkdir(root, 0777) < 0 && errno != EEXIST)
		return glint_error_set(errno, "capture root %s: %s", root,
				       strerror(errno));
	s = calloc(1, sizeof(*s));
	if (!s)
		return glint_error_set(ENOMEM, "out of memory");
	utc_stamp(stamp, sizeof(stamp), 1);
	for (int n = 0;; n++) {
		if (n == 0)
			snprintf(s->dir, sizeof(s->dir), "%s/%s-%s", root, kind,
				 stamp);
		else
			snprintf(s->dir, sizeof(s->dir), "%s/%s-%s-%d", root,
				 kind, stamp, n);
		if (mkdir(s->dir, 0777) == 0)
			break;
		if (errno != EEXIST || n > 999) {
			ret = glint_error_set(errno, "%s: %s", s->dir,
					      strerror(errno));
			free(s);
			return ret;
		}
	}
	ret = fsync_path(root);
	utc_stamp(stamp, sizeof(stamp), 0);
	s->doc = json_pack("{s:s, s:s, s:s, s:s, s:o, s:[]}", "glint",
			   GLINT_SESSION_VERSION, "kind", kind, "status",
			   "incomplete", "started", stamp, "camera",
			   camera_json(cam), "frames");
	if (!s->doc && ret == 0)
		ret = glint_error_set(ENOMEM, "out of memory");
	if (ret == 0 && rig_json) {
		ret = glint_path_join(path, sizeof(path), s->dir, "rig.json");
		if (ret == 0)
			ret = glint_atomic_write_file(path, rig_json,
						      strlen(rig_json));
	}
	if (ret == 0)
		ret = save_doc(s);
	if (ret == 0)
		ret = glint_path_join(path, sizeof(path), s->dir, "log.txt");
	if (ret == 0 && !(s->log = fopen(path, "a")))
		ret = glint_error_set(errno, "%s: %s", path, strerror(errno));
	if (ret < 0) {
		json_decref(s->doc);
		free(s);
		return ret;
	}
	*out = s;
	glint_session_log(s, "session %s: %s on %s (%s)", s->dir, kind,
			  cam->name, cam->backend);
	return 0;
}

const char *glint_session_dir(const struct glint_session *s)
{
	return s->dir;
}

void glint_session_log(struct glint_session *s, const char *fmt, ...)
{
	char stamp[32];
	va_list ap;
	if (!s->log)
		return;
	utc_stamp(stamp, sizeof(stamp), 0);
	fprintf(s->log, "%s ", stamp);
	va_start(ap, fmt);
	vfprintf(s->log, fmt, ap);
	va_end(ap);
	fputc('\n', s->log);
	fflush(s->log);
	fdatasync(fileno(s->log));
}

int glint_session_add_frame(struct glint_session *s,
			    const struct glint_frame *f, int index)
{
	char name[32], json_name[32], path[GLINT_PATH_MAX];
	char *meta = glint_frame_metadata_json(f, index);
	int ret;

	if (!meta)
		return glint_error_set(ENOMEM, "out of memory");
	snprintf(name, sizeof(name), "frame-%03d.dng", index);
	ret = glint_path_join(path, sizeof(path), s->dir, name);
	if (ret == 0)
		ret = glint_frame_write(path, f, meta);
	if (ret == 0) {
		snprintf(json_name, sizeof(json_name), "frame-%03d.json",
			 index);
		ret = glint_path_join(path, sizeof(path), s->dir, json_name);
	}
	if (ret == 0) {
		size_t n = strlen(meta);
		char *m = realloc(meta, n + 2);
		if (!m) {
			ret = glint_error_set(ENOMEM, "out of memory");
		} else {
			meta = m;
			meta[n] = '\n';
			ret = glint_atomic_write_file(path, meta, n + 1);
		}
	}
	free(meta);
	if (ret < 0)
		return ret;
	json_array_append_new(
		json_object_get(s->doc, "frames"),
		json_pack("{s:s, s:f, s:f, s:I}", "file", name, "exposure_s",
			  f->exposure_s, "gain", f->gain, "pixels_crc32",
			  (json_int_t)glint_frame_pixels_crc32(f)));
	glint_session_log(s, "frame %d: %g s, gain %g, sequence %llu", index,
			  f->exposure_s, f->gain,
			  (unsigned long long)f->sequence);
	return save_doc(s);
}

int glint_session_finish(struct glint_session *s, const struct glint_bracket *b,
			 const char *stage, const char *error,
			 const char *const *files)
{
	char stamp[32];
	int ret;

	utc_stamp(stamp, sizeof(stamp), 0);
	json_object_set_new(s->doc, "finished", json_string(stamp));
	if (b && b->n > 0)
		json_object_set_new(
			s->doc, "bracket",
			json_pack("{s:i, s:b, s:b, s:b, s:b, s:s?, s:b, s:f, "
				  "s:f, s:f, s:i, s:i}",
				  "frames", b->n, "covered_low", b->covered_low,
				  "covered_high", b->covered_high, "used_gain",
				  b->used_gain, "truncated", b->truncated,
				  "stopped_by",
				  b->stopped_by[0] ? b->stopped_by : NULL,
				  "camera_limit", b->camera_limit, "seconds",
				  b->seconds, "wall_seconds", b->wall_seconds,
				  "metered_start_s", b->metered_start_s,
				  "metering_frames", b->metering_frames,
				  "unclipped_superseded", b->superseded));
	if (error) {
		/* The capture itself did not finish (its frames are whole
		 * but too few): incomplete; a stage after it refused what
		 * it was given or could not write: failed. */
		int capture = !stage || !strcmp(stage, "bracket") ||
			      !strcmp(stage, "camera");
		json_object_set_new(
			s->doc, "status",
			json_string(capture ? "incomplete" : "failed"));
		json_object_set_new(s->doc, "stage",
				    json_string(stage ? stage : "bracket"));
		json_object_set_new(s->doc, "error", json_string(error));
		glint_session_log(s, "%s at the %s stage: %s",
				  capture ? "incomplete" : "failed",
				  stage ? stage : "bracket", error);
	} else {
		json_t *list = json_array();
		for (int i = 0; files && files[i]; i++)
			json_array_append_new(list, json_string(files[i]));
		json_object_set_new(s->doc, "files", list);
		json_object_set_new(s->doc, "status", json_string("complete"));
		glint_session_log(s, "complete: %d frames in %.2f s", b->n,
				  b->seconds);
	}
	ret = save_doc(s);
	if (s->log)
		fclose(s->log);
	json_decref(s->doc);
	free(s);
	return ret;
}

static int cmp_path(const void *a, const void *b)
{
	return strcmp(*(char *const *)a, *(char *const *)b);
}

static int list_add(char ***list, int *n, const char *path)
{
	char **grown = realloc(*list, (size_t)(*n + 1) * sizeof(char *));
	if (!grown)
		return glint_error_set(ENOMEM, "out of memory");
	*list = grown;
	grown[*n] = strdup(path);
	if (!grown[*n])
		return glint_error_set(ENOMEM, "out of memory");
	(*n)++;
	return 0;
}

static int collect(const char *dir, int depth, char ***list, int *n)
{
	char path[GLINT_PATH_MAX], sj[GLINT_PATH_MAX];
	struct dirent *e;
	struct stat st;
	int ret = 0;
	DIR *d = opendir(dir);

	if (!d)
		return 0; /* no sessions there */
	while (!ret && (e = readdir(d))) {
		if (e->d_name[0] == '.' || !strcmp(e->d_name, "queue"))
			continue;
		if (glint_path_join(path, sizeof(path), dir, e->d_name) < 0 ||
		    glint_path_join(sj, sizeof(sj), path, "session.json") < 0)
			continue; /* too long to be one of ours */
		if (stat(sj, &st) == 0)
			ret = list_add(list, n, path);
		else if (depth == 0 && stat(path, &st) == 0 &&
			 S_ISDIR(st.st_mode))
			ret = collect(path, 1, list, n);
	}
	closedir(d);
	return ret;
}

int glint_session_list(const char *root, char ***list, int *n)
{
	*list = NULL;
	*n = 0;
	int ret = collect(root, 0, list, n);
	if (ret < 0) {
		glint_session_list_free(*list, *n);
		*list = NULL;
		*n = 0;
		return ret;
	}
	if (*n > 1)
		qsort(*list, (size_t)*n, sizeof(char *), cmp_path);
	return 0;
}

void glint_session_list_free(char **list, int n)
{
	for (int i = 0; i < n; i++)
		free(list[i]);
	free(list);
}

int glint_session_fit_open(const char *dir, int wait,
			   struct glint_session_fit_files *fs, int *lock)
{
	char path[GLINT_PATH_MAX];
	int ret = glint_session_fit_inputs(dir, fs);

	if (ret == 0)
		ret = glint_path_join(path, sizeof(path), dir,
				      GLINT_SESSION_FIT_LOCK);
	if (ret < 0)
		return ret;
	ret = glint_lockfile_acquire(path, "glint fit", 0, lock);
	int waited = 0;
	struct timespec since;
	clock_gettime(CLOCK_REALTIME, &since);
	if (ret == -EBUSY && wait) {
		glint_log_info("%s", glint_error_msg());
		glint_log_info("waiting for it to finish");
		ret = glint_lockfile_acquire(path, "glint fit", 1, lock);
		waited = ret == 0;
	} else if (ret == -EBUSY) {
		glint_error_prefix(ret,
				   "%s is being fitted (use --wait to wait "
				   "for it)",
				   dir);
	}
	if (ret < 0)
		return ret;
	/* We hold the lock: what a killed fit left is ours to clean. */
	if (glint_atomic_dir_sweep(fs->out) > 0)
		glint_log_info("%s: cleaned up after an interrupted fit",
			       fs->out);
	/* the fit waited for finished with a result: that is the answer */
	struct stat st;
	if (waited &&
	    glint_path_join(path, sizeof(path), fs->out, "params.json") == 0 &&
	    stat(path, &st) == 0 &&
	    (st.st_mtim.tv_sec > since.tv_sec ||
	     (st.st_mtim.tv_sec == since.tv_sec &&
	      st.st_mtim.tv_nsec >= since.tv_nsec)))
		return 1;
	return 0;
}

void glint_session_summarize(const char *dir, struct glint_session_summary *s)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	json_t *doc = NULL;

	memset(s, 0, sizeof(*s));
	if (glint_path_join(path, sizeof(path), dir, GLINT_SESSION_JSON) == 0)
		doc = glint_json_read_quiet(path);
	const char *kind = json_string_value(json_object_get(doc, "kind"));
	const char *status = json_string_value(json_object_get(doc, "status"));
	const char *err = json_string_value(json_object_get(doc, "error"));
	glint_text(s->kind, sizeof(s->kind), "%s", kind ? kind : "?");
	glint_text(s->status, sizeof(s->status), "%s",
		   status ? status : "unreadable");
	glint_text(s->error, sizeof(s->error), "%s", err ? err : "");
	s->frames = (int)json_array_size(json_object_get(doc, "frames"));
	json_decref(doc);
	glint_error_clear();
	s->fitted = glint_path_join(path, sizeof(path), dir,
				    GLINT_SESSION_FIT "/params.json") == 0 &&
		    stat(path, &st) == 0;
	/* one of its run's samples, fitted jointly? */
	struct glint_run_samples *rs = malloc(sizeof(*rs));
	char run[GLINT_PATH_MAX];
	const char *slash = strrchr(dir, '/');
	if (rs && slash &&
	    glint_path_fmt(run, sizeof(run), "%.*s", (int)(slash - dir), dir) ==
		    0 &&
	    glint_run_read(run, rs) > 0 &&
	    glint_path_join(path, sizeof(path), rs->out, "params.json") == 0 &&
	    stat(path, &st) == 0)
		for (int k = 0; k < rs->n; k++)
			s->run_fitted |=
				!strcmp(strrchr(rs->session[k], '/'), slash);
	free(rs);
	glint_error_clear();
}

json_t *glint_session_fit_params(const char *dir)
{
	char path[GLINT_PATH_MAX];

	if (glint_path_join(path, sizeof(path), dir,
			    GLINT_SESSION_FIT "/params.json") < 0) {
		glint_error_clear();
		return NULL;
	}
	return glint_json_read_quiet(path);
}

int glint_run_write(const char *dir, const struct glint_run_samples *rs)
{
	char path[GLINT_PATH_MAX];
	json_t *list = json_array(), *doc = json_pack("{s:o}", "samples", list);
	int ret = doc ? 0 : glint_error_set(ENOMEM, "out of memory");

	for (int k = 0; k < rs->n && ret == 0; k++) {
		const char *name = strrchr(rs->session[k], '/');
		name = name ? name + 1 : rs->session[k];
		if (json_array_append_new(
			    list, json_pack("{s:s, s:i}", "session", name,
					    "light", rs->light[k])) < 0)
			ret = glint_error_set(ENOMEM, "out of memory");
	}
	char *text = ret ? NULL : json_dumps(doc, JSON_INDENT(2));
	if (ret == 0 && !text)
		ret = glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = glint_path_join(path, sizeof(path), dir, GLINT_RUN_JSON);
	if (ret == 0)
		ret = glint_atomic_write_file(path, text, strlen(text));
	free(text);
	json_decref(doc);
	return ret;
}

int glint_run_read(const char *dir, struct glint_run_samples *rs)
{
	char path[GLINT_PATH_MAX];
	struct stat st;
	int ret = glint_path_join(path, sizeof(path), dir, GLINT_RUN_JSON);

	memset(rs, 0, sizeof(*rs));
	if (ret < 0)
		return ret;
	if (lstat(path, &st) < 0)
		return errno == ENOENT ? 0
				       : glint_error_set(errno, "%s: %s", path,
							 strerror(errno));
	json_t *doc = NULL;
	ret = glint_json_load(path, &doc);
	if (ret < 0)
		return ret;
	json_t *list = json_object_get(doc, "samples");
	size_t n = json_array_size(list);
	if (n < 1 || n > GLINT_RUN_MAX_SAMPLES)
		ret = glint_error_set(EINVAL,
				      "%s: samples: expected a list of 1..%d "
				      "sample sessions",
				      path, GLINT_RUN_MAX_SAMPLES);
	for (size_t k = 0; k < n && ret == 0; k++) {
		json_t *e = json_array_get(list, k);
		const char *name =
			json_string_value(json_object_get(e, "session"));
		json_t *light = json_object_get(e, "light");
		/* a plain folder name: a run names nothing outside itself */
		if (!name || !name[0] || strchr(name, '/') ||
		    !strcmp(name, ".") || !strcmp(name, "..") ||
		    (light && !json_is_integer(light)))
			ret = glint_error_set(EINVAL,
					      "%s: samples[%zu]: expected "
					      "{\"session\": a folder name in "
					      "the run, \"light\": a lamp "
					      "number}",
					      path, k);
		else
			ret = glint_path_join(rs->session[k],
					      sizeof(rs->session[k]), dir,
					      name);
		rs->light[k] = (int)json_integer_value(light);
	}
	json_decref(doc);
	if (ret == 0)
		ret = glint_path_join(rs->out, sizeof(rs->out), dir,
				      GLINT_SESSION_FIT);
	if (ret < 0)
		return ret;
	rs->n = (int)n;
	return 1;
}

int glint_fit_target_check(const char *dir)
{
	struct glint_run_samples *rs = malloc(sizeof(*rs));
	struct glint_session_fit_files *fs = malloc(sizeof(*fs));
	int ret = rs && fs ? glint_run_read(dir, rs)
			   : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = glint_session_fit_inputs(dir, fs);
	for (int k = 0; ret > 0 && k < rs->n; k++)
		if (glint_session_fit_inputs(rs->session[k], fs) < 0)
			ret = glint_error_prefix(-EINVAL, "run %s", dir);
	free(rs);
	free(fs);
	return ret < 0 ? ret : 0;
}
