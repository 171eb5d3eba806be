/* SPDX-License-Identifier: MIT */
/*
 * A fit narrowed to the sphere's window (glint_fit_job_crop), and one
 * whose G-buffer is sparse as well (GLINT_GBUFFER_MB=0: hits held only
 * for the fitted pixels, rows traced again to render), give the whole
 * frame's answer: the same parameters and standard errors to the last
 * bit, the same misfit, the same final render inside the window, and a
 * render.exr whose display window is the frame and whose data window is
 * where the window lies.  The photo: an off-centre Table-1 sphere from the
 * reference renderer, with a weight image (so the final render's noise
 * check runs).  A photo of the wrong size is left alone.
 *
 * `test_fit_window pilot`: a sphere 240 px in radius, whose final render
 * is sized by its pilot of every 16th row (fit/job.c): the pilot is
 * reported, the render's noise is below the target or what held it is
 * named, and no row is left unrendered.
 */
#include "test.h"
#include "exr_windows.h"

#include "core/error.h"
#include "core/image.h"
#include "fit/job.h"
#include "sim_scene.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[] = "/tmp/glint-window-XXXXXX";

static json_t *run(struct glint_fit_job *job, const char *name, int crop,
		   int sparse)
{
	static char dirs[3][512];
	json_t *doc = NULL;
	int k = crop + sparse;
	snprintf(dirs[k], sizeof(dirs[k]), "%s/%s", tmpdir, name);
	job->out_dir = dirs[k];
	setenv("GLINT_GBUFFER_MB", sparse ? "0" : "1e9", 1);
	if (crop)
		CHECK(glint_fit_job_crop(job) == 0, "%s", glint_error_msg());
	CHECK(glint_fit_job_run(job, &doc) == 0, "%s: %s", name,
	      glint_error_msg());
	return doc;
}

/* b's parameters and misfit are a's, to the last bit. */
static void same_answer(json_t *a, json_t *b, const char *what)
{
	json_t *pa = json_object_get(a, "parameters"),
	       *pb = json_object_get(b, "parameters");
	CHECK(json_array_size(pa) == json_array_size(pb) &&
		      json_array_size(pa) > 0,
	      "%s: %zu and %zu parameters", what, json_array_size(pa),
	      json_array_size(pb));
	for (size_t k = 0; k < json_array_size(pa); k++) {
		json_t *x = json_array_get(pa, k), *y = json_array_get(pb, k);
		const char *name =
			json_string_value(json_object_get(x, "name"));
		double va = json_real_value(json_object_get(x, "value"));
		double vb = json_real_value(json_object_get(y, "value"));
		double sa = json_real_value(json_object_get(x, "stderr"));
		double sb = json_real_value(json_object_get(y, "stderr"));
		printf("%-8s %-11s %.9f %.9f  stderr %.9f %.9f\n", what, name,
		       va, vb, sa, sb);
		CHECK(va == vb && sa == sb,
		      "%s: %s: %.12g +- %.12g in the frame, %.12g +- %.12g",
		      what, name, va, sa, vb, sb);
	}
	json_t *ma = json_object_get(a, "misfit"),
	       *mb = json_object_get(b, "misfit");
	CHECK(ma && mb && json_equal(ma, mb), "%s: misfit differs", what);
}

/* The render in dir, inside the window, is the frame's render ra. */
static void same_render(const struct glint_image *ra, const char *dir, int wx,
			int wy, int ww, int wh)
{
	char path[600];
	struct glint_image *rb = NULL;
	snprintf(path, sizeof(path), "%s/%s/render.exr", tmpdir, dir);
	CHECK(glint_image_read(path, &rb) == 0, "%s", glint_error_msg());
	if (!rb)
		return;
	CHECK(rb->width == ww && rb->height == wh, "%s: render %dx%d", dir,
	      rb->width, rb->height);
	double worst = 0;
	for (int y = 0; y < wh && rb->width == ww && rb->height == wh; y++)
		for (int x = 0; x < ww; x++)
			for (int c = 0; c < 3; c++) {
				double u =
					glint_image_px(ra, wx + x, wy + y)[c];
				double v = glint_image_px(rb, x, y)[c];
				worst = fmax(worst,
					     fabs(u - v) / fmax(u, 1e-3));
			}
	printf("%s render: largest relative difference %.3g\n", dir, worst);
	CHECK(worst <= 1e-6,
	      "%s: the window's render differs from the "
	      "frame's by %.3g",
	      dir, worst);
	glint_image_free(rb);
	exr_attr_box2i_t dw, disp;
	CHECK(test_exr_windows(path, &dw, &disp) == 0, "%s's windows", path);
	CHECK(dw.min.x == wx && dw.min.y == wy && dw.max.x == wx + ww - 1 &&
		      dw.max.y == wy + wh - 1 && disp.min.x == 0 &&
		      disp.max.x == 191 && disp.max.y == 191,
	      "data window (%d,%d)-(%d,%d), display (%d,%d)-(%d,%d)", dw.min.x,
	      dw.min.y, dw.max.x, dw.max.y, disp.min.x, disp.min.y, disp.max.x,
	      disp.max.y);
}

static struct glint_fit_job job_of(const struct glint_scene *sc,
				   const struct glint_model *m,
				   const struct glint_image *photo,
				   const struct glint_image *weight)
{
	struct glint_fit_job job;
	memset(&job, 0, sizeof(job));
	job.scene_path = "test";
	job.photo_path = "test";
	job.scene = *sc;
	job.model = m;
	job.photo = glint_image_dup(photo);
	job.weight = weight ? glint_image_dup(weight) : NULL;
	glint_fit_default_opts(&job.opts);
	job.no_auto_select = 1;
	job.accept_rmse = 10; /* the comparison is the point, not the verdict */
	/* the render's samples from the photo's noise alone, not from how
	 * fast this machine is at the moment */
	job.render_budget_s = 1e9;
	return job;
}

/* A w x h weight image of 1 / variance for a 1 % noise on the mean
 * signal. */
static struct glint_image *flat_weights(int w, int h)
{
	struct glint_image *img = glint_image_new(w, h);
	for (size_t i = 0; img && i < (size_t)w * h * 3; i++)
		img->data[i] = 1e4f;
	return img;
}

/* Yellow plastic (Table 1) and the renderer of scene sc; 0 or -1. */
static int setup(const struct glint_scene *sc, const struct glint_model **m,
		 double *truth, struct glint_renderer *r)
{
	CHECK(mkdtemp(tmpdir) != NULL, "mkdtemp");
	CHECK(glint_material_load(GLINT_DATA_DIR "/paper-table1.json",
				  "yellow-plastic", m, truth) == 0,
	      "%s", glint_error_msg());
	CHECK(glint_renderer_init(r, sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	return test_failures ? -1 : 0;
}

static void remove_tmpdir(void)
{
	test_remove_dir(tmpdir);
}

/* A pixel's mean value. */
static double px_mean(const struct glint_image *img, int x, int y)
{
	const float *v = glint_image_px(img, x, y);
	return (v[0] + v[1] + v[2]) / 3;
}

static int pilot(void)
{
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];

	sim_scene_192(&sc, GLINT_DATA_DIR "/env/venice_sunset_1k.hdr", -114);
	glint_pinhole_init(&sc.cam, 560, 560, 0.1, 0.036 / 560, 0, 0,
			   v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0));
	sc.sphere_centre = v3(0, 0, -0.32);
	if (setup(&sc, &m, truth, &r) < 0)
		return test_result();
	struct glint_image *photo = glint_image_new(560, 560);
	struct glint_reference_opts ro;
	glint_reference_default_opts(&ro);
	ro.spp = 4;
	ro.samples = 16;
	CHECK(photo && glint_reference_render(&r.scene, r.env, m, truth, &ro,
					      photo) == 0,
	      "%s", glint_error_msg());
	glint_renderer_release(&r);
	struct glint_image *weight = flat_weights(560, 560);
	struct glint_fit_job job = job_of(&sc, m, photo, weight);
	/* A budget no render of every pixel meets, even at an eighth of the
	 * samples: the render shades a grid and interpolates (the step
	 * comes from the pilot's time, at most 8). */
	job.render_budget_s = 0.01;
	json_t *doc = photo && weight ? run(&job, "pilot", 1, 0) : NULL;
	int h = job.scene.cam.height, w = job.scene.cam.width;
	printf("window %dx%d of 560x560\n", w, h);
	CHECK(h >= 512, "the window has %d rows: the pilot needs 512", h);
	json_t *ren = json_object_get(doc, "render");
	json_t *pl = json_object_get(ren, "pilot");
	double f1 = json_real_value(json_object_get(pl, "first_pair_factor"));
	double q = json_real_value(json_object_get(ren, "noise"));
	const char *lim = json_string_value(json_object_get(ren, "limited_by"));
	printf("pilot noise %.4f, first pair at %.3f of the scene's samples; "
	       "render noise %.4f (%s), %.1f s\n",
	       json_real_value(json_object_get(pl, "noise")), f1, q,
	       lim ? lim : "below target",
	       json_real_value(json_object_get(ren, "seconds")));
	CHECK(json_integer_value(json_object_get(pl, "row_step")) == 17 &&
		      f1 >= 0.125 && f1 <= 1,
	      "render.pilot: step %lld, factor %g",
	      (long long)json_integer_value(json_object_get(pl, "row_step")),
	      f1);
	CHECK(q > 0 && (q <= 0.25 || lim), "render noise %g, limited by %s", q,
	      lim ? lim : "nothing said");
	long long step = json_integer_value(json_object_get(ren, "pixel_step"));
	printf("pixel step %lld\n", step);
	CHECK(step > 1 && step <= 8 && lim && strstr(lim, "time"),
	      "render.pixel_step %lld (limited by %s): expected a grid", step,
	      lim ? lim : "nothing said");
	/* Every row through the sphere's middle column is rendered (a row
	 * the pilot skipped and the pair missed would stay 0), and every
	 * column through its middle row; both near the photo there. */
	char path[600];
	struct glint_image *ri = NULL;
	snprintf(path, sizeof(path), "%s/pilot/render.exr", tmpdir);
	CHECK(glint_image_read(path, &ri) == 0, "%s", glint_error_msg());
	int dark = 0;
	double dev = 0;
	int ndev = 0;
	for (int y = h / 4; ri && y < 3 * h / 4; y++)
		dark += !(px_mean(ri, w / 2, y) > 0);
	for (int x = w / 4; ri && x < 3 * w / 4; x++)
		dark += !(px_mean(ri, x, h / 2) > 0);
	CHECK(ri && !dark, "%d rows or columns through the sphere are black",
	      dark);
	/* Each value is as noisy as the samples the budget left; their
	 * sum, over the middle row and column, is not. */
	double sum_p = 0;
	for (int k = -h / 5; ri && ri->width == 560 && k <= h / 5; k++) {
		int c = 280; /* the frame's middle: the sphere's */
		dev += px_mean(ri, c, c + k) + px_mean(ri, c + k, c);
		sum_p += px_mean(photo, c, c + k) + px_mean(photo, c + k, c);
		ndev += 2;
	}
	printf("render - photo through the middle: %+.2f %% of the photo\n",
	       sum_p > 0 ? 100 * (dev / sum_p - 1) : NAN);
	CHECK(ndev && sum_p > 0 && fabs(dev / sum_p - 1) < 0.02,
	      "the render is %+.1f %% off the photo through the sphere's "
	      "middle (%d values)",
	      sum_p > 0 ? 100 * (dev / sum_p - 1) : NAN, ndev);
	glint_image_free(ri);
	json_decref(doc);
	glint_fit_job_unload(&job);
	glint_image_free(photo);
	glint_image_free(weight);
	remove_tmpdir();
	return test_result();
}

int main(int argc, char **argv)
{
	if (argc > 1 && !strcmp(argv[1], "pilot"))
		return pilot();
	struct glint_scene sc;
	struct glint_renderer r;
	const struct glint_model *m;
	double truth[GLINT_MAX_PARAMS];

	sim_scene_192(&sc, GLINT_DATA_DIR "/env/venice_sunset_1k.hdr", -114);
	sc.sphere_centre =
		v3(0.035, -0.02, -0.5); /* right of and below centre */
	if (setup(&sc, &m, truth, &r) < 0)
		return test_result();
	struct glint_image *photo = sim_photo(&r, m, truth);
	glint_renderer_release(&r);
	CHECK(photo != NULL, "%s", glint_error_msg());
	if (!photo)
		return test_result();
	/* GLINT_GBUFFER_MB=0 does make the renderer's G-buffer sparse. */
	setenv("GLINT_GBUFFER_MB", "0", 1);
	CHECK(glint_renderer_init(&r, &sc, 0, NULL) == 0, "%s",
	      glint_error_msg());
	CHECK(!r.gb.hits && r.gb.slot && r.gb.cover && !r.gb.nstored,
	      "the G-buffer is not sparse");
	glint_renderer_release(&r);
	struct glint_image *weight = flat_weights(192, 192);

	struct glint_fit_job full = job_of(&sc, m, photo, weight);
	struct glint_fit_job win = job_of(&sc, m, photo, weight);
	struct glint_fit_job sparse = job_of(&sc, m, photo, weight);
	json_t *a = run(&full, "full", 0, 0), *b = run(&win, "window", 1, 0);
	json_t *c = run(&sparse, "sparse", 1, 1);
	CHECK(!full.window.frame_width, "the whole frame was cropped");
	CHECK(win.window.frame_width == 192 && win.window.frame_height == 192,
	      "window frame %dx%d", win.window.frame_width,
	      win.window.frame_height);
	int wx = win.window.x, wy = win.window.y;
	int ww = win.scene.cam.width, wh = win.scene.cam.height;
	printf("window %dx%d at (%d, %d): %.0f %% of the frame\n", ww, wh, wx,
	       wy, 100.0 * ww * wh / (192 * 192));
	CHECK(wx > 20 && wy > 20 && wx + ww <= 192 && wy + wh <= 192 &&
		      ww * wh < 0.75 * 192 * 192,
	      "window %dx%d at (%d, %d)", ww, wh, wx, wy);
	if (!a || !b || !c)
		goto out;
	same_answer(a, b, "window");
	same_answer(a, c, "sparse");

	/* The final render: the frame's inside the window. */
	char path[600];
	struct glint_image *ra = NULL;
	snprintf(path, sizeof(path), "%s/full/render.exr", tmpdir);
	CHECK(glint_image_read(path, &ra) == 0, "%s", glint_error_msg());
	if (ra && ra->width == 192) {
		same_render(ra, "window", wx, wy, ww, wh);
		same_render(ra, "sparse", wx, wy, ww, wh);
	}
	glint_image_free(ra);
	json_t *jw = json_object_get(json_object_get(b, "render"), "window");
	CHECK(json_integer_value(json_object_get(jw, "x")) == wx &&
		      json_integer_value(json_object_get(jw, "width")) == ww &&
		      json_integer_value(json_object_get(jw, "frame_width")) ==
			      192,
	      "params.json render.window");
	double bs = json_real_value(json_object_get(
		json_object_get(b, "render"), "budget_seconds"));
	CHECK(bs == 1e9, "render.budget_seconds %g: expected the job's 1e9",
	      bs);

	/* A photo that is not the camera's size is left for the fit to
	 * refuse. */
	struct glint_fit_job odd = job_of(&sc, m, photo, NULL);
	glint_image_free(odd.photo);
	odd.photo = glint_image_new(100, 100);
	CHECK(glint_fit_job_crop(&odd) == 0 && !odd.window.frame_width &&
		      odd.scene.cam.width == 192,
	      "a 100x100 photo for a 192x192 camera was cropped");
	glint_fit_job_unload(&odd);
out:
	json_decref(a);
	json_decref(b);
	json_decref(c);
	glint_fit_job_unload(&full);
	glint_fit_job_unload(&win);
	glint_fit_job_unload(&sparse);
	glint_image_free(photo);
	glint_image_free(weight);
	remove_tmpdir();
	return test_result();
}
