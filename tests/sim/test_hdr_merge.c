/* SPDX-License-Identifier: MIT */
/*
 * The linear HDR merge against ground truth: a bracket of the simulated
 * camera's test card (known radiance, noisy sensor) merges to the true
 * radiance per photosite with z-scores (error / predicted sigma) of mean
 * ~0 and spread ~1, i.e. the variance image predicts the actual error;
 * clipped samples do not leak in; a bumped frame is flagged; bad brackets
 * fail clearly; the demosaic keeps values and propagates variances.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera/bracket.h"
#include "capture/hdr/hdr_linear.h"
#include "core/error.h"
#include "sim/camera_sim.h"
#include "sim/sensor.h"

#define W 96
#define H 64

static int bracket(const char *dev, struct glint_bracket *b)
{
	struct glint_fake_clock fc = { 0 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_camera *cam;
	struct glint_bracket_opts o;
	struct glint_roi all = { 0, 0, 0, 0 };
	int ret = glint_camera_open("sim", dev, &clk, &cam);
	if (ret == 0) {
		glint_bracket_default_opts(&o);
		ret = glint_bracket_capture(cam, &all, &o, &clk, b);
	}
	glint_camera_close(cam);
	return ret;
}

/* True x = L k c per site (DN per second at unity gain). */
static double truth(const struct glint_image *card, int x, int y)
{
	struct glint_sensor s;
	glint_sensor_default(&s);
	int c = (x & 1) + (y & 1); /* RGGB */
	return glint_image_px(card, x, y)[c] * s.k * s.gain;
}

/* The test card as the sensor receives it: through the camera's lens
 * and optical low-pass filter (sim/sensor.h), as the sim camera shows
 * it. */
static struct glint_image *sensor_card(void)
{
	struct glint_sensor s;
	struct glint_image *card = glint_sim_test_card(W, H, 6);
	glint_sensor_default(&s);
	if (card && glint_sensor_optics(&s, card) < 0) {
		glint_image_free(card);
		card = NULL;
	}
	return card;
}

static void test_round_trip(void)
{
	struct glint_bracket b;
	struct glint_raw_hdr h;
	struct glint_hdr_report rep;
	struct glint_noise_model nm;
	char dev[96];

	snprintf(dev, sizeof(dev), "sim:width=%d,height=%d,seed=7", W, H);
	CHECK(bracket(dev, &b) == 0, "%s", glint_error_msg());
	glint_noise_default(&nm);
	CHECK(glint_hdr_merge_raw(b.frames, b.n, &nm, &h, &rep) == 0, "%s",
	      glint_error_msg());
	if (!h.x)
		return;
	struct glint_image *card = sensor_card();
	double sz = 0, szz = 0, worst_rel = 0;
	long n = 0, tail = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			size_t s = (size_t)y * W + x;
			if (!h.valid[s])
				continue;
			double t = truth(card, x, y);
			double z = (h.x[s] - t) / sqrt(h.var[s]);
			sz += z;
			szz += z * z;
			tail += fabs(z) > 4;
			n++;
			if (sqrt(h.var[s]) < 0.01 * t)
				worst_rel =
					fmax(worst_rel, fabs(h.x[s] / t - 1));
		}
	double mean = sz / n, sd = sqrt(szz / n - mean * mean);
	printf("%d frames, %ld sites valid of %ld: z mean %+.3f, sd %.3f, "
	       "%ld beyond 4 sigma; worst relative error where sigma < 1 %%: "
	       "%.4f\n",
	       b.n, n, rep.sites, mean, sd, tail, worst_rel);
	CHECK(n == rep.sites, "%ld invalid sites: the bracket covers all",
	      rep.sites - n);
	CHECK(fabs(mean) < 0.05, "z mean %g: the merge is biased", mean);
	CHECK(sd > 0.9 && sd < 1.1,
	      "z spread %g: the variance does not predict the error", sd);
	CHECK(tail < 0.002 * n, "%ld of %ld sites beyond 4 sigma", tail, n);
	CHECK(worst_rel < 0.05, "worst relative error %g", worst_rel);
	CHECK(!rep.moved, "a still bracket was flagged as moved");

	/* The disk clips in every frame but the shortest ones: were clipped
	 * samples used, it would read low.  Its sites are inside the z
	 * check above; check its mean too. */
	double sum = 0, want = 0;
	int k = 0;
	for (int y = H / 2 - 2; y <= H / 2 + 1; y++)
		for (int x = (int)(0.7 * W) - 2; x <= (int)(0.7 * W) + 1;
		     x++, k++) {
			sum += h.x[(size_t)y * W + x];
			want += truth(card, x, y);
		}
	CHECK(fabs(sum / want - 1) < 0.01, "disk reads %g of its radiance",
	      sum / want);

	/* A bumped rig: one frame shifted by two pixels. */
	int mid = b.n / 2;
	uint16_t *d = b.frames[mid].data;
	memmove(d + 2, d, ((size_t)W * H - 2) * sizeof(uint16_t));
	struct glint_raw_hdr h2;
	CHECK(glint_hdr_merge_raw(b.frames, b.n, &nm, &h2, &rep) == -EINVAL,
	      "a bracket with a frame shifted by 2 px was merged");
	CHECK_MSG(glint_error_msg(), "disagree beyond their noise");
	CHECK_MSG(glint_error_msg(), "refused");
	double worst = 0;
	for (int i = 0; i < rep.pairs; i++)
		worst = fmax(worst, rep.disagree[i]);
	printf("bumped frame %d: worst pair disagrees on %.1f %% of sites\n",
	       mid, 100 * worst);
	CHECK(rep.moved, "a frame shifted by 2 px was not flagged");

	/* Demosaic keeps the sites' own values and their variances. */
	struct glint_image *rgb, *var, *valid;
	CHECK(glint_hdr_demosaic(&h, &rgb, &var, &valid) == 0, "%s",
	      glint_error_msg());
	if (rgb) {
		/* (1, 1) is a B site; its G is the mean of 4 G sites. */
		double g = (h.x[1 * W + 0] + h.x[1 * W + 2] + h.x[0 * W + 1] +
			    h.x[2 * W + 1]) /
			   4;
		double gv = (h.var[1 * W + 0] + h.var[1 * W + 2] +
			     h.var[0 * W + 1] + h.var[2 * W + 1]) /
			    16;
		CHECK_NEAR(glint_image_px(rgb, 1, 1)[2], h.x[1 * W + 1],
			   1e-6 * h.x[1 * W + 1], "own value kept");
		CHECK_NEAR(glint_image_px(rgb, 1, 1)[1], g, 1e-5 * g,
			   "bilinear G at a B site");
		CHECK_NEAR(glint_image_px(var, 1, 1)[1], gv, 1e-5 * gv,
			   "variance of a 4-site mean");
		CHECK(glint_image_px(valid, 1, 1)[0] == 1, "valid");
		glint_image_free(rgb);
		glint_image_free(var);
		glint_image_free(valid);
	}
	glint_raw_hdr_release(&h);
	glint_image_free(card);
	glint_bracket_release(&b);
}

static struct glint_frame flat(int w, int h, uint16_t v, double e)
{
	struct glint_frame f;
	memset(&f, 0, sizeof(f));
	f.width = w;
	f.height = h;
	f.channels = 1;
	f.linear = 1;
	f.bit_depth = 12;
	f.black_level = 64;
	f.exposure_s = e;
	f.gain = 1;
	snprintf(f.format, sizeof(f.format), "RGGB16");
	f.data = malloc((size_t)w * h * sizeof(uint16_t));
	for (int i = 0; i < w * h; i++)
		f.data[i] = v;
	return f;
}

static void expect_error(struct glint_frame *f, int n, const char *frag)
{
	struct glint_raw_hdr h;
	struct glint_noise_model nm;
	glint_noise_default(&nm);
	CHECK(glint_hdr_merge_raw(f, n, &nm, &h, NULL) < 0 && !h.x,
	      "merged a bad bracket (%s)", frag);
	CHECK_MSG(glint_error_msg(), frag);
	/* The streaming merge: the same error, at the frame or at the end. */
	struct glint_hdr_stream *st;
	int ret = glint_hdr_stream_new(&nm, &st);
	for (int i = 0; i < n && ret == 0; i++)
		ret = glint_hdr_stream_add(st, &f[i]);
	if (ret == 0)
		ret = glint_hdr_stream_finish(st, &h, NULL);
	CHECK(ret < 0 && !h.x, "the stream merged a bad bracket (%s)", frag);
	CHECK_MSG(glint_error_msg(), frag);
	glint_hdr_stream_free(st);
}

static void test_bad_brackets(void)
{
	struct glint_frame f[2];
	f[0] = flat(8, 8, 1000, 0.01);
	f[1] = flat(8, 6, 1000, 0.02);
	expect_error(f, 2, "must match");
	glint_frame_release(&f[1]);
	f[1] = flat(8, 8, 1000, 0);
	expect_error(f, 2, "exposure 0 s");
	glint_frame_release(&f[1]);
	f[1] = flat(8, 8, 4095, 0.02);
	glint_frame_release(&f[0]);
	f[0] = flat(8, 8, 4095, 0.01);
	expect_error(f, 2, "clipped everywhere");
	glint_frame_release(&f[0]);
	glint_frame_release(&f[1]);
	f[0] = flat(8, 8, 64, 0.01);
	f[1] = flat(8, 8, 64, 0.02);
	expect_error(f, 2, "black");
	f[1].channels = 3;
	f[1].linear = 0;
	expect_error(f, 2, "camera-encoded");
	expect_error(f, 0, "no frames");
	glint_frame_release(&f[0]);
	glint_frame_release(&f[1]);
}

/* z-scores of a merge against the card's truth. */
static void zstats(const struct glint_raw_hdr *h,
		   const struct glint_image *card, double *mean, double *sd,
		   long *tail, long *n)
{
	double sz = 0, szz = 0;
	*tail = *n = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			size_t s = (size_t)y * W + x;
			if (!h->valid[s])
				continue;
			double z =
				(h->x[s] - truth(card, x, y)) / sqrt(h->var[s]);
			sz += z;
			szz += z * z;
			*tail += fabs(z) > 4;
			(*n)++;
		}
	*mean = sz / *n;
	*sd = sqrt(szz / *n - *mean * *mean);
}

static int stream_merge(struct glint_frame *f, int n, const int *order,
			const struct glint_noise_model *nm,
			struct glint_raw_hdr *h, struct glint_hdr_report *rep)
{
	struct glint_hdr_stream *st;
	int ret = glint_hdr_stream_new(nm, &st);
	for (int i = 0; i < n && ret == 0; i++)
		ret = glint_hdr_stream_add(st, &f[order ? order[i] : i]);
	if (ret == 0)
		ret = glint_hdr_stream_finish(st, h, rep);
	glint_hdr_stream_free(st);
	return ret;
}

/*
 * The streaming merge (frames folded in as they come, one held back)
 * against the truth as the batch merge is, and against the batch merge
 * itself: each frame's weight from an estimate its own noise is not in.
 * In the bracket's order (going up) and backwards.
 */
static void test_stream(void)
{
	struct glint_bracket b;
	struct glint_raw_hdr hb, hs;
	struct glint_hdr_report rb, rs;
	struct glint_noise_model nm;
	char dev[96];
	int order[GLINT_BRACKET_MAX];

	/* More sites than the round trip: the z statistics' own noise. */
	snprintf(dev, sizeof(dev), "sim:width=%d,height=%d,seed=11", W, H);
	CHECK(bracket(dev, &b) == 0, "%s", glint_error_msg());
	glint_noise_default(&nm);
	CHECK(glint_hdr_merge_raw(b.frames, b.n, &nm, &hb, &rb) == 0, "%s",
	      glint_error_msg());
	struct glint_image *card = sensor_card();
	for (int pass = 0; pass < 2 && hb.x; pass++) {
		for (int i = 0; i < b.n; i++)
			order[i] = pass ? b.n - 1 - i : i;
		CHECK(stream_merge(b.frames, b.n, order, &nm, &hs, &rs) == 0,
		      "%s", glint_error_msg());
		if (!hs.x)
			break;
		double mean, sd, bmean, bsd;
		long tail, n, btail, bn;
		zstats(&hs, card, &mean, &sd, &tail, &n);
		zstats(&hb, card, &bmean, &bsd, &btail, &bn);
		/* Against the batch merge, in units of its sigma. */
		double dmax = 0, dsum = 0, vr_lo = 1, vr_hi = 1, vr_sum = 0;
		long nd = 0;
		for (size_t s = 0; s < (size_t)W * H; s++) {
			if (!hb.valid[s] || !hs.valid[s])
				continue;
			double d = fabs(hs.x[s] - hb.x[s]) / sqrt(hb.var[s]);
			dmax = fmax(dmax, d);
			dsum += d;
			nd++;
			vr_lo = fmin(vr_lo, hs.var[s] / hb.var[s]);
			vr_hi = fmax(vr_hi, hs.var[s] / hb.var[s]);
			vr_sum += hs.var[s] / hb.var[s];
		}
		printf("stream %s: z mean %+.3f sd %.3f (batch %+.3f, %.3f), "
		       "%ld beyond 4 sigma; against the batch: mean %.4f, "
		       "worst %.3f sigma, variance ratio %.3f..%.3f (mean "
		       "%.4f); "
		       "invalid %ld (%ld), dark %ld (%ld)\n",
		       pass ? "backwards" : "going up", mean, sd, bmean, bsd,
		       tail, dsum / nd, dmax, vr_lo, vr_hi, vr_sum / nd,
		       rs.invalid_sites, rb.invalid_sites, rs.dark_sites,
		       rb.dark_sites);
		CHECK(n == bn && rs.invalid_sites == rb.invalid_sites,
		      "valid sites %ld, batch %ld", n, bn);
		CHECK(fabs(mean) < 0.05, "z mean %g: the stream is biased",
		      mean);
		CHECK(sd > 0.9 && sd < 1.1, "z spread %g", sd);
		CHECK(tail < 0.002 * n, "%ld of %ld beyond 4 sigma", tail, n);
		CHECK(dsum / nd < 0.05,
		      "mean difference from the batch %g "
		      "sigma",
		      dsum / nd);
		/* Evaluated at its own estimate: where a dark site's estimate
		 * differs, so does its shot noise (the z spread above says
		 * both are honest). */
		CHECK(fabs(vr_sum / nd - 1) < 0.02 && vr_lo > 0.6 &&
			      vr_hi < 1.6,
		      "variance %g..%g of the batch's (mean %g)", vr_lo, vr_hi,
		      vr_sum / nd);
		CHECK(rs.frames == b.n && rs.pairs == b.n - 1 && !rs.moved,
		      "report: %d frames, %d pairs, moved %d", rs.frames,
		      rs.pairs, rs.moved);
		glint_raw_hdr_release(&hs);
	}

	/* A bumped frame is flagged, as by the batch merge. */
	int mid = b.n / 2;
	uint16_t *d = b.frames[mid].data;
	memmove(d + 2, d, ((size_t)W * H - 2) * sizeof(uint16_t));
	CHECK(stream_merge(b.frames, b.n, NULL, &nm, &hs, &rs) == -EINVAL,
	      "the stream merged a bracket with a frame shifted by 2 px");
	CHECK_MSG(glint_error_msg(), "disagree beyond their noise");
	CHECK(rs.moved, "the stream missed a frame shifted by 2 px");

	/* No more frames than the mask has bits; none after a failure. */
	struct glint_hdr_stream *st;
	int ret = glint_hdr_stream_new(&nm, &st);
	for (int i = 0; i <= GLINT_HDR_STREAM_MAX && ret == 0; i++)
		ret = glint_hdr_stream_add(st, &b.frames[i % b.n]);
	CHECK(ret < 0, "a %d-frame stream was accepted",
	      GLINT_HDR_STREAM_MAX + 1);
	CHECK_MSG(glint_error_msg(), "at most 32 frames");
	CHECK(glint_hdr_stream_add(st, &b.frames[0]) < 0,
	      "a frame added after a failure");
	CHECK(glint_hdr_stream_finish(st, &hs, NULL) < 0 && !hs.x,
	      "a failed stream finished");
	glint_hdr_stream_free(st);
	glint_raw_hdr_release(&hb);
	glint_image_free(card);
	glint_bracket_release(&b);
}

/*
 * A lamp too small to resolve, through the sim camera's optics, its Bayer
 * mosaic and glint's demosaic: each channel's total flux within 1 % of
 * the lamp's, on whichever site of the mosaic the lamp falls and whatever
 * its colour.  Without the optical low-pass
 * filter the mosaic aliases it (a red lamp on a green site loses its red):
 * the check shows it does, so that it can fail.
 */
static double point_flux_error(int olpf, double sigma, int px, int py,
			       const double colour[3])
{
	const int w = 24, h = 24;
	struct glint_sensor s;
	struct glint_image *img = glint_image_new(w, h);
	struct glint_raw_hdr r = { .width = w, .height = h };
	struct glint_image *rgb = NULL, *var = NULL, *valid = NULL;
	double worst = 0;

	glint_sensor_default(&s);
	s.olpf = olpf;
	s.psf_sigma_px = sigma;
	r.x = malloc((size_t)w * h * sizeof(float));
	r.var = calloc((size_t)w * h, sizeof(float));
	r.valid = malloc((size_t)w * h);
	snprintf(r.format, sizeof(r.format), "RGGB16");
	if (!img || !r.x || !r.var || !r.valid)
		goto out;
	/* a lamp of 1000 units in one pixel (a rendered pixel is its
	 * area's mean: any lamp inside it) on black */
	for (int c = 0; c < 3; c++)
		glint_image_px(img, px, py)[c] = (float)(1000 * colour[c]);
	CHECK(glint_sensor_optics(&s, img) == 0, "%s", glint_error_msg());
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			int c = (x & 1) + (y & 1); /* RGGB, as the sim camera */
			r.x[y * w + x] = glint_image_px(img, x, y)[c];
			r.valid[y * w + x] = 1;
		}
	CHECK(glint_hdr_demosaic(&r, &rgb, &var, &valid) == 0, "%s",
	      glint_error_msg());
	if (!rgb)
		goto out;
	for (int c = 0; c < 3; c++) {
		double sum = 0, truth = 1000 * colour[c];
		for (int i = 0; i < w * h; i++)
			sum += rgb->data[3 * i + c];
		/* relative to the lamp's brightest channel: a channel the lamp
		 * lacks has no flux to keep */
		worst = fmax(worst, fabs(sum - truth) / 1000);
	}
out:
	glint_image_free(img);
	glint_image_free(rgb);
	glint_image_free(var);
	glint_image_free(valid);
	free(r.x);
	free(r.var);
	free(r.valid);
	return worst;
}

static void test_point_source_flux(void)
{
	static const double colours[3][3] = { { 1, 0.15, 0.002 },
					      { 0.3, 1, 0.2 },
					      { 0.05, 0.3, 1 } };
	double worst = 0, bare = 0, split = 0;
	for (int k = 0; k < 3; k++)
		for (int py = 10; py <= 13; py++)
			for (int px = 10; px <= 13; px++) {
				worst = fmax(worst,
					     point_flux_error(1, 0.6, px, py,
							      colours[k]));
				bare = fmax(bare, point_flux_error(0, 0, px, py,
								   colours[k]));
				/* the split alone: a sharp lens */
				split = fmax(split,
					     point_flux_error(1, 0, px, py,
							      colours[k]));
			}
	printf("point source through lens + OLPF + demosaic: worst flux "
	       "error %.4f of the lamp's; the OLPF alone %.4f; without the "
	       "optics %.3f\n",
	       worst, split, bare);
	CHECK(worst < 0.01, "flux error %.4f: expected under 1 %%", worst);
	CHECK(split < 0.01, "flux error %.4f with the OLPF alone", split);
	CHECK(bare > 0.5,
	      "without the optics the mosaic should alias a point (error "
	      "%.3f)",
	      bare);
}

/* The demosaic as its header states it, site by site: the reference the
 * library's precomputed taps must match to the bit. */
static int colour_at(const char *fmt, int x, int y)
{
	if (!strncmp(fmt, "MONO", 4))
		return -1;
	char c = fmt[(y & 1) * 2 + (x & 1)];
	return c == 'R' ? 0 : c == 'G' ? 1 : 2;
}

static void test_demosaic_reference(void)
{
	static const char *const fmts[] = { "RGGB16", "GBRG16", "BGGR16",
					    "MONO16" };
	const int w = 37, h = 23; /* odd: both parities at every edge */
	struct glint_raw_hdr r = { .width = w, .height = h };
	r.x = malloc((size_t)w * h * sizeof(float));
	r.var = malloc((size_t)w * h * sizeof(float));
	r.valid = malloc((size_t)w * h);
	srand(3);
	for (int i = 0; i < w * h; i++) {
		r.x[i] = (float)rand() / 7;
		r.var[i] = (float)rand() / 9;
		r.valid[i] = rand() % 5 != 0;
	}
	for (int f = 0; f < 4; f++) {
		struct glint_image *rgb, *var, *valid;
		long wrong = 0;
		snprintf(r.format, sizeof(r.format), "%s", fmts[f]);
		CHECK(glint_hdr_demosaic(&r, &rgb, &var, &valid) == 0, "%s",
		      glint_error_msg());
		if (!rgb)
			continue;
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++) {
				int own = colour_at(fmts[f], x, y), ok = 1;
				float er[3], ev[3];
				for (int c = 0; c < 3; c++) {
					int rad = own == c || own < 0 ? 0 : 1,
					    k = 0;
					double sx = 0, sv = 0;
					for (int dy = -rad; dy <= rad; dy++)
						for (int dx = -rad; dx <= rad;
						     dx++) {
							int xx = x + dx,
							    yy = y + dy;
							if (xx < 0 || yy < 0 ||
							    xx >= w || yy >= h)
								continue;
							int cc = colour_at(
								fmts[f], xx,
								yy);
							size_t s =
								(size_t)yy * w +
								xx;
							if ((cc >= 0 &&
							     cc != c) ||
							    !r.valid[s])
								continue;
							sx += r.x[s];
							sv += r.var[s];
							k++;
						}
					if (!k) {
						ok = 0;
						er[c] = r.x[y * w + x];
						ev[c] = 0;
						continue;
					}
					er[c] = (float)(sx / k);
					ev[c] = (float)(sv / ((double)k * k));
				}
				for (int c = 0; c < 3; c++) {
					float v = ok ? ev[c] : 0;
					wrong += glint_image_px(rgb, x, y)[c] !=
							 er[c] ||
						 glint_image_px(var, x, y)[c] !=
							 v ||
						 glint_image_px(valid, x,
								y)[c] !=
							 (float)ok;
				}
			}
		CHECK(wrong == 0, "%s: %ld values differ from the reference",
		      fmts[f], wrong);
		glint_image_free(rgb);
		glint_image_free(var);
		glint_image_free(valid);
	}
	glint_raw_hdr_release(&r);
}

int main(void)
{
	glint_backends_register();
	RUN(test_round_trip);
	RUN(test_stream);
	RUN(test_demosaic_reference);
	RUN(test_point_source_flux);
	RUN(test_bad_brackets);
	return test_result();
}
