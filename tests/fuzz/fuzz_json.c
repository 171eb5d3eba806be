/* SPDX-License-Identifier: MIT */
/* glint's JSON files: the same bytes as a scene, a material (or a fit's
 * params.json), a rig file, a probe's light sources (env-sources.json), a
 * capture session's session.json, a run's run.json and a queue's job
 * file. */
#define _DEFAULT_SOURCE /* mkdtemp */
#include "fuzz.h"

#include "appliance/queue.h"
#include "appliance/rig.h"
#include "capture/hdr/session.h"
#include "capture/hdr/session_merge.h"
#include "capture/probe/probe_sources.h"
#include "fit/brdf/model.h"
#include "fit/scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A session folder and a queue, made once, removed at exit. */
static char dir[64], session_json[128], run_json[128], queue[128], job[160];

static void remove_dirs(void)
{
	static const char *const states[] = { "pending", "running", "done",
					      "failed", "cancelled" };
	char p[192];
	unlink(session_json);
	unlink(run_json);
	unlink(job);
	for (int i = 0; i < 5; i++) {
		snprintf(p, sizeof(p), "%s/%s", queue, states[i]);
		rmdir(p);
	}
	rmdir(queue);
	rmdir(dir);
}

static int make_dirs(void)
{
	snprintf(dir, sizeof(dir), "%s", "/tmp/glint-fuzz-json.XXXXXX");
	if (!mkdtemp(dir))
		return -1;
	snprintf(session_json, sizeof(session_json), "%s/session.json", dir);
	snprintf(run_json, sizeof(run_json), "%s/run.json", dir);
	snprintf(queue, sizeof(queue), "%s/queue", dir);
	snprintf(job, sizeof(job), "%s/pending/fuzz-job.json", queue);
	atexit(remove_dirs);
	return glint_queue_init(queue);
}

static void put(const char *path, const uint8_t *data, size_t size)
{
	FILE *f = fopen(path, "wb");
	if (!f)
		abort();
	if (size && fwrite(data, 1, size, f) != size)
		abort();
	fclose(f);
}

static int seen(const struct glint_job *j, void *ctx)
{
	(void)j;
	(*(int *)ctx)++;
	return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static int ready;
	if (!ready && make_dirs() < 0)
		abort();
	ready = 1;
	const char *path = fuzz_path(data, size);
	struct glint_scene scene;
	glint_scene_load(path, &scene);
	const struct glint_model *model;
	double params[GLINT_MAX_PARAMS];
	glint_material_load(path, NULL, &model, params);
	glint_material_load(path, "fuzz", &model, params);
	struct glint_rig rig;
	glint_rig_load(path, &rig);
	glint_rig_free(&rig);
	struct glint_light_sources sources;
	glint_probe_sources_read(path, &sources);

	/* As a session's session.json: what glint fit SESSION and the HDR
	 * merge read from it. */
	put(session_json, data, size);
	struct glint_session_fit_files fs;
	glint_session_fit_inputs(dir, &fs);
	struct glint_noise_model nm;
	glint_session_noise(dir, &nm);
	struct glint_frame *frames = NULL;
	int n = 0;
	glint_session_load_frames(dir, &frames, &n);
	glint_frames_free(frames, n); /* the caller's, also on failure */

	/* As a run's run.json (its samples' sessions). */
	put(run_json, data, size);
	struct glint_run_samples rs;
	glint_run_read(dir, &rs);
	unlink(run_json);

	/* As a job file waiting in the queue. */
	put(job, data, size);
	int jobs = 0;
	glint_queue_list(queue, seen, &jobs);
	return 0;
}
