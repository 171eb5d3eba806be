/* SPDX-License-Identifier: MIT */
/*
 * glint probe unwrap | convert | register | calibrate: light-probe processing
 * (capture/probe/probe.h, docs/hdr.md).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"

#include "capture/probe/probe.h"
#include "capture/probe/probe_calibrate.h"
#include "capture/probe/probe_sources.h"
#include "capture/probe/probe_register.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"
#include "core/output.h"
#include "core/path.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* What every subcommand's page ends with. */
static void probe_help_footer(void)
{
	printf("\nAn existing output is refused unless --force, which "
	       "replaces only files glint\nwrote (never another's, never an "
	       "input).  Every input is light: an 8-bit\nimage (.png, .jpg, "
	       "...) is refused as not radiance, unless --srgb (then\n"
	       "linearised through the sRGB curve).\n"
	       "\nExit status: 0 done, 1 bad input, 2 bad command line.\n");
}

static void unwrap_help(void)
{
	printf("usage: glint probe unwrap PHOTO.exr --focal-px F [--ball "
	       "CX,CY,R] [options] -o ENV.exr\n"
	       "\n"
	       "A photographed mirror ball (HDR, linear) to a "
	       "lat-long map in the\ncamera's frame (+Y up, the camera "
	       "looking along -Z: the map's centre), with\nthe rig's "
	       "perspective camera (each pixel's own view ray, not the "
	       "orthographic\napproximation), divided by the ball's "
	       "reflectance at each angle.  Also writes\nENV-mask.png "
	       "(white = reliable: not grazing, not on the blurred rim, not "
	       "the\ncamera's own reflection), ENV-density.exr (photo "
	       "pixels per steradian, for\nblending two views) and "
	       "ENV-sources.json: light sources too small for the photo\nto "
	       "resolve (the sun, a small lamp), found, measured (direction, "
	       "flux, colour,\ntheir uncertainty) and put into the map as "
	       "points (docs/hdr.md); ENV-preview.png:\nthe map with those "
	       "sources ringed and numbered, the unreliable directions\n"
	       "darkened.  PHOTO-variance.exr and PHOTO-weights.exr beside "
	       "the photo (a\nmerge's) give their noise and clipping.\n"
	       "\n"
	       "  -o, --output ENV.exr the map (and the files named above "
	       "beside it)\n"
	       "  --focal-px F         focal length in pixels\n"
	       "  --principal X,Y      principal point (default: the image "
	       "centre)\n"
	       "  --ball CX,CY,R       the ball's image circle, pixels "
	       "(default: found in the\n"
	       "                       photo, as capture does; a given one "
	       "is checked)\n"
	       "  --srgb               take an 8-bit photo as sRGB-encoded "
	       "(else refused: not\n"
	       "                       radiance)\n"
	       "  --chrome N,K         complex index of the ball (default "
	       "3.2,3.3: chrome, 55 %%)\n"
	       "  --reflectivity R     a constant reflectance instead\n"
	       "  --grazing DEG        unreliable beyond this incidence "
	       "(default 80)\n"
	       "  --size WxH           output size (default 4R x 2R, at least "
	       "720 x 360\n"
	       "                       when it holds a compact source)\n"
	       "  --orthographic       the peers' approximation, for "
	       "comparison\n"
	       "  --no-sources         leave compact light sources as "
	       "photographed\n"
	       "  --psf-sigma PX       the camera's blur (lens and demosaic, "
	       "1 sigma; default 0):\n"
	       "                       the rim within 3 sigma of the blur "
	       "is unreliable\n"
	       "  --olpf               the camera has an optical low-pass "
	       "filter (adds its split)\n"
	       "  --no-fill            leave the unreliable directions "
	       "behind the ball as\n"
	       "                       photographed (default: interpolated "
	       "from around them)\n"
	       "  --force              replace outputs glint wrote\n");
	probe_help_footer();
}

static void calibrate_help(void)
{
	printf("usage: glint probe calibrate ENV.exr GRAY.exr --focal-px F "
	       "--albedo A [--ball CX,CY,R]\n"
	       "                             [options] -o OUT.exr\n"
	       "\n"
	       "The unwrapped probe ENV.exr corrected by a photo of a matte "
	       "gray ball of known\nalbedo taken by the same camera from "
	       "the same place (the gray half of a\ngray/chrome pair): per "
	       "channel, the map's scale and the flux of each compact\n"
	       "source of ENV-sources.json (a sun clipped in the probe's "
	       "shortest frame, a\nlamp whose colour the mosaic aliased) "
	       "as the gray ball's shading shows them,\nwith their "
	       "uncertainty (docs/hdr.md, \"Calibration by a gray "
	       "ball\").  Writes\nOUT.exr, OUT-sources.json and "
	       "OUT-calibration.json; GRAY-weights.exr beside\nthe photo "
	       "(a merge's) keeps clipped pixels out.\n"
	       "\n"
	       "  -o, --output OUT.exr the calibrated map (and the files "
	       "named above)\n"
	       "  --focal-px F         focal length of the gray ball's "
	       "photo, pixels\n"
	       "  --principal X,Y      principal point (default: the image "
	       "centre)\n"
	       "  --ball CX,CY,R       the gray ball's image circle, pixels "
	       "(default: found)\n"
	       "  --albedo A | R,G,B   the ball's diffuse albedo (its "
	       "specification, or measured)\n"
	       "  --albedo-sigma S | R,G,B  its 1-sigma uncertainty "
	       "(default 0)\n"
	       "  --srgb               take 8-bit images as sRGB-encoded\n"
	       "  --force              replace outputs glint wrote\n");
	probe_help_footer();
}

static void convert_help(void)
{
	printf("usage: glint probe convert IN OUT --from FMT --to FMT "
	       "[--size WxH] [--srgb]\n"
	       "\n"
	       "A light probe from one mapping to another: latlong, angular "
	       "(Debevec's light\nprobe format), cross (vertical cube "
	       "cross) and ball (ideal mirror ball,\northographic); "
	       "orientations in docs/hdr.md.  The default size keeps the "
	       "angular\nresolution.\n"
	       "\n"
	       "  --from FMT, --to FMT latlong, angular, cross or ball\n"
	       "  --size WxH           output size\n"
	       "  --srgb               take an 8-bit image as sRGB-encoded\n"
	       "  --force              replace an output glint wrote\n");
	probe_help_footer();
}

static void register_help(void)
{
	printf("usage: glint probe register ENV1.exr ENV2.exr -o OUT.exr "
	       "[--yaw DEG] [--points F] [--srgb]\n"
	       "\n"
	       "Two unwrapped views of the probe (the second photo ~90 "
	       "degrees away) to one\nmap in view 1's frame: the rotation "
	       "from --points (a file of lines\n'x1 y1 x2 y2', lat-long "
	       "pixel positions of the same feature in each map;\nleast "
	       "squares), else automatically from --yaw (the rough turn "
	       "about +Y) by\nthe best agreement where both views are "
	       "reliable; then the views are blended,\neach weighted by its "
	       "mask x sampling density (the -mask.png and -density.exr\n"
	       "written by unwrap, when present).\n"
	       "\n"
	       "  -o, --output OUT.exr the blended map\n"
	       "  --yaw DEG            the rough turn between the views "
	       "(default 90)\n"
	       "  --points F           matched points, one 'x1 y1 x2 y2' a "
	       "line\n"
	       "  --srgb               take 8-bit maps as sRGB-encoded\n"
	       "  --force              replace an output glint wrote\n");
	probe_help_footer();
}

void cmd_probe_help(void)
{
	printf("usage: glint probe unwrap PHOTO.exr --focal-px F [--ball "
	       "CX,CY,R] [options] -o ENV.exr\n"
	       "       glint probe convert IN OUT --from FMT --to FMT "
	       "[--size WxH] [--srgb]\n"
	       "       glint probe register ENV1.exr ENV2.exr -o OUT.exr "
	       "[--yaw DEG] [--points F] [--srgb]\n"
	       "       glint probe calibrate ENV.exr GRAY.exr --focal-px F "
	       "--albedo A -o OUT.exr\n"
	       "\n"
	       "Light probes: a mirror-ball photo to the environment map a "
	       "fit is lit by.\n"
	       "\n"
	       "subcommands (glint probe SUB --help: its options):\n"
	       "  unwrap     a mirror-ball photo to a lat-long map, its small "
	       "lights measured\n"
	       "  convert    a light probe between lat-long, angular, cube "
	       "cross and ball\n"
	       "  register   two unwrapped views of the probe to one map\n"
	       "  calibrate  a map's scale and its small lights' flux from a "
	       "gray ball's photo\n");
	probe_help_footer();
}

/* OUT and its siblings (OUT less its extension, then each suffix; ""
 * is OUT itself) by the one overwrite rule (core/output.h), the inputs
 * (NULL-terminated) never replaced. */
static int outputs_check(const char *out, const char *const *suffixes,
			 int force, const char *const *inputs)
{
	char path[GLINT_PATH_MAX];
	for (int k = 0; suffixes[k]; k++) {
		int ret = *suffixes[k] ? glint_path_sibling(path, sizeof(path),
							    out, suffixes[k])
				       : 0;
		if (ret == 0)
			ret = glint_output_check(*suffixes[k] ? path : out,
						 force, inputs);
		if (ret < 0)
			return ret;
	}
	return 0;
}

/* N numbers separated by ',' or 'x' ("640,480", "1024x512") into a
 * struct numbers. */
struct numbers {
	int n, given;
	double v[3];
};

static int parse_numbers(const char *arg, void *dest)
{
	struct numbers *nb = dest;
	char buf[256];
	int k = 0;
	snprintf(buf, sizeof(buf), "%s", arg);
	for (char *save = NULL, *t = strtok_r(buf, ",x", &save); t;
	     t = strtok_r(NULL, ",x", &save)) {
		char *end;
		double d = strtod(t, &end);
		if (*end || !isfinite(d) || k == nb->n)
			break;
		nb->v[k++] = d;
	}
	if (k != nb->n || strchr(",x", arg[strlen(arg) - 1]))
		return glint_error_set(EINVAL, "expected %d number%s", nb->n,
				       nb->n > 1 ? "s, e.g. 1,2" : "");
	nb->given = 1;
	return 0;
}

/* PHOTO-variance.exr or PHOTO-weights.exr beside a merged photo (PHOTO
 * without its extension), when it is there and the photo's size; NULL
 * else (the sources' flux then has no noise term, clipping is not seen). */
static struct glint_image *merge_sibling(const char *photo_path,
					 const char *suffix,
					 const struct glint_image *photo)
{
	char path[GLINT_PATH_MAX];
	struct glint_image *img = NULL;
	struct stat st;
	if (glint_path_sibling(path, sizeof(path), photo_path, suffix) < 0 ||
	    stat(path, &st) < 0) {
		glint_error_clear();
		return NULL;
	}
	if (glint_image_read(path, &img) < 0 || img->width != photo->width ||
	    img->height != photo->height) {
		glint_log_warn("%s: not used (%s)", path,
			       img ? "not the photo's size"
				   : glint_error_msg());
		glint_error_clear();
		glint_image_free(img);
		return NULL;
	}
	glint_log_info("%s: the merge's %s", path,
		       suffix[1] == 'v' ? "variance" : "weights");
	return img;
}

/* The ball photo's camera and circle options (--focal-px, --principal,
 * --ball) into o. */
struct ball_args {
	struct numbers f, pp, ball;
};

#define BALL_ARGS_INIT                                                         \
	{                                                                      \
		.f = { .n = 1 }, .pp = { .n = 2 }, .ball = {.n = 3 }           \
	}
#define BALL_OPTS(b)                                                           \
	CMD_CALL("focal-px", &(b).f, parse_numbers),                           \
		CMD_CALL("principal", &(b).pp, parse_numbers),                 \
		CMD_CALL("ball", &(b).ball, parse_numbers)

static void ball_args_apply(const struct ball_args *b,
			    struct glint_unwrap_opts *o)
{
	if (b->f.given)
		o->fpx = b->f.v[0];
	if (b->pp.given) {
		o->cx = b->pp.v[0];
		o->cy = b->pp.v[1];
	}
	if (b->ball.given) {
		o->ball_cx = b->ball.v[0];
		o->ball_cy = b->ball.v[1];
		o->ball_r = b->ball.v[2];
	}
}

static int unwrap_main(int argc, char **argv)
{
	struct glint_unwrap_opts o;
	const char *out = NULL;
	struct ball_args ba = BALL_ARGS_INIT;
	struct numbers chrome = { .n = 2 }, size = { .n = 2 };
	int srgb = 0, force = 0;

	glint_unwrap_default_opts(&o);
	const struct cmd_opt opts[] = {
		BALL_OPTS(ba),
		CMD_CALL("chrome", &chrome, parse_numbers),
		CMD_REAL("reflectivity", &o.reflectivity, 1e-6, 1),
		CMD_REAL("grazing", &o.grazing_deg, 0, 90),
		CMD_CALL("size", &size, parse_numbers),
		CMD_FLAG("orthographic", 0, &o.orthographic),
		CMD_FLAG("no-sources", 0, &o.no_sources),
		CMD_REAL("psf-sigma", &o.psf_sigma_px, 0, 8),
		CMD_FLAG("olpf", 0, &o.olpf),
		CMD_FLAG("no-fill", 0, &o.no_fill),
		CMD_FLAG("srgb", 0, &srgb),
		CMD_FLAG("force", 0, &force),
		CMD_STRING("output", 'o', &out),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("probe unwrap", unwrap_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	ball_args_apply(&ba, &o);
	int have_ball = ba.ball.given;
	for (int k = 0; k < 3 && chrome.given; k++) {
		o.n[k] = chrome.v[0];
		o.k[k] = chrome.v[1];
	}
	if (size.given) {
		o.width = (int)size.v[0];
		o.height = (int)size.v[1];
	}
	argc = a.argc;
	argv = a.argv;
	if (argc != 1 || !out)
		return cmd_usage_error("probe", "unwrap: expected PHOTO and -o "
						"ENV.exr");
	if (!(o.fpx > 0))
		return cmd_usage_error("probe", "unwrap: --focal-px is "
						"required");
	struct glint_image *photo = NULL;
	int w, h;
	static const char *const siblings[] = { "",
						"-mask.png",
						"-density.exr",
						"-sources.json",
						"-preview.png",
						NULL };
	const char *inputs[] = { argv[0], NULL };
	if (outputs_check(out, siblings, force, inputs) < 0)
		return cmd_fail("probe");
	int ret = glint_image_read_radiance(argv[0], srgb, &photo);
	if (ret == 0 && (ret = glint_probe_find_ball(photo, have_ball, &o)) < 0)
		glint_error_prefix(ret, "%s", argv[0]);
	struct glint_image *var = NULL, *wt = NULL;
	if (ret == 0 && !o.no_sources) {
		var = merge_sibling(argv[0], "-variance.exr", photo);
		wt = merge_sibling(argv[0], "-weights.exr", photo);
	}
	o.variance = var;
	o.weights = wt;
	if (ret == 0)
		ret = glint_probe_unwrap_write(photo, &o, out, &w, &h);
	if (ret == 0)
		glint_log_info("%s -> %s (%dx%d), mask, density%s beside it",
			       argv[0], out, w, h,
			       o.no_sources ? "" : " and sources");
	glint_image_free(photo);
	glint_image_free(var);
	glint_image_free(wt);
	return ret < 0 ? cmd_fail("probe") : GLINT_EXIT_OK;
}

/* One number for all three channels, or three. */
static int parse_rgb(const char *arg, void *dest)
{
	struct numbers *nb = dest;
	nb->n = strchr(arg, ',') ? 3 : 1;
	if (parse_numbers(arg, dest) < 0)
		return glint_error_set(EINVAL, "expected one number or three "
					       "(R,G,B)");
	if (nb->n == 1)
		nb->v[1] = nb->v[2] = nb->v[0];
	nb->n = 3;
	return 0;
}

static int calibrate_main(int argc, char **argv)
{
	struct glint_unwrap_opts geom;
	struct glint_calibrate_opts co;
	const char *out = NULL;
	struct ball_args ba = BALL_ARGS_INIT;
	struct numbers alb = { .n = 3 }, alb_sigma = { .n = 3 };
	int srgb = 0, force = 0;

	glint_unwrap_default_opts(&geom);
	glint_calibrate_default_opts(&co);
	const struct cmd_opt opts[] = {
		BALL_OPTS(ba),
		CMD_CALL("albedo", &alb, parse_rgb),
		CMD_CALL("albedo-sigma", &alb_sigma, parse_rgb),
		CMD_FLAG("srgb", 0, &srgb),
		CMD_FLAG("force", 0, &force),
		CMD_STRING("output", 'o', &out),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("probe calibrate", calibrate_help, opts, argc,
				  argv, &a);
	if (r)
		return cmd_options_exit(r);
	if (a.argc != 2 || !out)
		return cmd_usage_error("probe", "calibrate: expected ENV GRAY "
						"and -o OUT.exr");
	if (!ba.f.given || !alb.given)
		return cmd_usage_error("probe", "calibrate: --focal-px and "
						"--albedo are required");
	ball_args_apply(&ba, &geom);
	for (int c = 0; c < 3; c++) {
		co.albedo[c] = alb.v[c];
		co.albedo_sigma[c] = alb_sigma.given ? alb_sigma.v[c] : 0;
	}
	const char *env_path = a.argv[0], *gray_path = a.argv[1];
	static const char *const siblings[] = { "", "-sources.json",
						"-calibration.json", NULL };
	const char *inputs[] = { env_path, gray_path, NULL };
	if (outputs_check(out, siblings, force, inputs) < 0)
		return cmd_fail("probe");

	struct glint_image *env = NULL, *gray = NULL, *wt = NULL;
	struct glint_light_sources src, *sp = NULL;
	struct glint_calibration cal;
	char path[GLINT_PATH_MAX];
	int ret = glint_image_read_radiance(env_path, srgb, &env);
	if (ret == 0)
		ret = glint_path_sibling(path, sizeof(path), env_path,
					 "-sources.json");
	if (ret == 0) {
		ret = glint_probe_sources_read(path, &src);
		if (ret == 0)
			sp = &src;
		else if (ret == -ENOENT) {
			glint_log_info("%s: none; the map's scale alone", path);
			glint_error_clear();
			ret = 0;
		}
	}
	if (ret == 0)
		ret = glint_image_read_radiance(gray_path, srgb, &gray);
	if (ret == 0 &&
	    (ret = glint_probe_find_ball(gray, ba.ball.given, &geom)) < 0)
		glint_error_prefix(ret, "%s", gray_path);
	if (ret == 0)
		co.weights = wt =
			merge_sibling(gray_path, "-weights.exr", gray);
	if (ret == 0)
		ret = glint_probe_calibrate(env, sp, gray, &geom, &co, &cal);
	if (ret == 0) {
		glint_probe_calibration_apply(&cal, env, sp);
		ret = glint_image_write(out, env, NULL);
	}
	if (ret == 0 && sp &&
	    (ret = glint_path_sibling(path, sizeof(path), out,
				      "-sources.json")) == 0)
		ret = glint_probe_sources_write(path, env_path, sp);
	if (ret == 0 && (ret = glint_path_sibling(path, sizeof(path), out,
						  "-calibration.json")) == 0)
		ret = glint_probe_calibration_write(path, env_path, gray_path,
						    &cal);
	if (ret == 0 && a.json) {
		json_t *doc = NULL;
		if (glint_json_load(path, &doc) == 0)
			cmd_print_json(doc);
	} else if (ret == 0) {
		printf("gray ball: %d pixels, relative RMS %.3f %.3f %.3f\n",
		       cal.pixels, cal.rel_rms[0], cal.rel_rms[1],
		       cal.rel_rms[2]);
		printf("  map scale    %.4f %.4f %.4f  (+- %.4f %.4f %.4f)\n",
		       cal.scale[0], cal.scale[1], cal.scale[2],
		       cal.scale_sigma[0], cal.scale_sigma[1],
		       cal.scale_sigma[2]);
		for (int k = 0; k < cal.nsources; k++) {
			const struct glint_calibrated_source *cs = &cal.src[k];
			printf("  source %d     %.4g %.4g %.4g  (+- %.2g %.2g "
			       "%.2g) from the %s; the probe had %.4g %.4g "
			       "%.4g%s\n",
			       k + 1, cs->flux[0], cs->flux[1], cs->flux[2],
			       cs->flux_sigma[0], cs->flux_sigma[1],
			       cs->flux_sigma[2],
			       cs->from_gray ? "gray ball" : "probe x scale",
			       cs->flux_probe[0], cs->flux_probe[1],
			       cs->flux_probe[2],
			       cs->saturated ? " (clipped: a lower bound)"
					     : "");
		}
		printf("  -> %s, its -sources.json and -calibration.json\n",
		       out);
	}
	glint_image_free(env);
	glint_image_free(gray);
	glint_image_free(wt);
	return ret < 0 ? cmd_fail("probe") : GLINT_EXIT_OK;
}

static int convert_main(int argc, char **argv)
{
	enum glint_probe_format from = GLINT_PROBE_LATLONG,
				to = GLINT_PROBE_LATLONG;
	const char *fs = NULL, *ts = NULL;
	struct numbers size = { .n = 2 };
	int srgb = 0, force = 0;
	const struct cmd_opt opts[] = {
		CMD_STRING("from", 0, &fs),
		CMD_STRING("to", 0, &ts),
		CMD_CALL("size", &size, parse_numbers),
		CMD_FLAG("srgb", 0, &srgb),
		CMD_FLAG("force", 0, &force),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("probe convert", convert_help, opts, argc,
				  argv, &a);
	if (r)
		return cmd_options_exit(r);
	double v[2] = { size.v[0], size.v[1] };
	argc = a.argc;
	argv = a.argv;
	if (argc != 2 || !fs || !ts)
		return cmd_usage_error("probe",
				       "convert: expected IN OUT --from "
				       "FMT --to FMT");
	if (glint_probe_format_parse(fs, &from) < 0 ||
	    glint_probe_format_parse(ts, &to) < 0)
		return cmd_usage_error("probe", "%s", glint_error_msg());
	static const char *const same[] = { "", NULL };
	const char *inputs[] = { argv[0], NULL };
	if (outputs_check(argv[1], same, force, inputs) < 0)
		return cmd_fail("probe");
	struct glint_image *src = NULL, *dst = NULL;
	int ret = glint_image_read_radiance(argv[0], srgb, &src);
	if (ret == 0 && (ret = glint_probe_convert(src, from, to, (int)v[0],
						   (int)v[1], &dst)) < 0)
		glint_error_prefix(ret, "%s", argv[0]);
	if (ret == 0)
		ret = glint_image_write(argv[1], dst, NULL);
	if (ret == 0)
		glint_log_info("%s (%s) -> %s (%s, %dx%d)", argv[0], fs,
			       argv[1], ts, dst->width, dst->height);
	glint_image_free(src);
	glint_image_free(dst);
	return ret < 0 ? cmd_fail("probe") : GLINT_EXIT_OK;
}

static int register_main(int argc, char **argv)
{
	const char *out = NULL, *points = NULL;
	double yaw = 90;
	int srgb = 0, force = 0;
	const struct cmd_opt opts[] = {
		CMD_REAL("yaw", &yaw, -360, 360), CMD_FLAG("srgb", 0, &srgb),
		CMD_STRING("points", 0, &points), CMD_FLAG("force", 0, &force),
		CMD_STRING("output", 'o', &out),  { 0 },
	};
	struct cmd_args args;
	int pr = cmd_options_parse("probe register", register_help, opts, argc,
				   argv, &args);
	if (pr)
		return cmd_options_exit(pr);
	int json = args.json;
	argc = args.argc;
	argv = args.argv;
	if (argc != 2 || !out)
		return cmd_usage_error("probe", "register: expected ENV1 ENV2 "
						"-o OUT");
	static const char *const same[] = { "", NULL };
	const char *inputs[] = { argv[0], argv[1], NULL };
	if (outputs_check(out, same, force, inputs) < 0)
		return cmd_fail("probe");
	struct glint_image *e1 = NULL, *e2 = NULL, *w1, *w2, *blend = NULL;
	struct mat3 r;
	double quality = NAN;
	int ret = glint_image_read_radiance(argv[0], srgb, &e1);
	if (ret == 0)
		ret = glint_image_read_radiance(argv[1], srgb, &e2);
	w1 = ret == 0 ? glint_probe_view_weight(argv[0]) : NULL;
	w2 = ret == 0 ? glint_probe_view_weight(argv[1]) : NULL;
	if (ret == 0 && points) {
		ret = glint_register_points_file(points, e1, e2, &r, &quality);
	} else if (ret == 0) {
		struct mat3 guess = m3_rotation_xyz_deg(0, yaw, 0);
		ret = glint_register_auto(e1, w1, e2, w2, &guess, &r, &quality);
	}
	if (ret == 0)
		ret = glint_probe_blend(e1, w1, e2, w2, &r, &blend);
	if (ret == 0)
		ret = glint_image_write(out, blend, NULL);
	if (ret == 0) {
		struct mat3 id = m3_rotation_xyz_deg(0, 0, 0);
		double ang = glint_rotation_angle_deg(&id, &r);
		glint_log_info("view 2 turned %.2f deg into view 1 (%s %.4g); "
			       "blend -> %s",
			       ang, points ? "residual deg RMS" : "cost",
			       quality, out);
		if (json)
			cmd_print_json(json_pack(
				"{s:[[f,f,f],[f,f,f],[f,f,f]], s:f, s:s}",
				"rotation", r.m[0][0], r.m[0][1], r.m[0][2],
				r.m[1][0], r.m[1][1], r.m[1][2], r.m[2][0],
				r.m[2][1], r.m[2][2], "angle_deg", ang,
				"output", out));
	}
	glint_image_free(e1);
	glint_image_free(e2);
	glint_image_free(w1);
	glint_image_free(w2);
	glint_image_free(blend);
	return ret < 0 ? cmd_fail("probe") : GLINT_EXIT_OK;
}

int cmd_probe(int argc, char **argv)
{
	if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
		cmd_probe_help();
		return argc < 2 ? GLINT_EXIT_USAGE : GLINT_EXIT_OK;
	}
	if (!strcmp(argv[1], "unwrap"))
		return unwrap_main(argc - 1, argv + 1);
	if (!strcmp(argv[1], "convert"))
		return convert_main(argc - 1, argv + 1);
	if (!strcmp(argv[1], "register"))
		return register_main(argc - 1, argv + 1);
	if (!strcmp(argv[1], "calibrate"))
		return calibrate_main(argc - 1, argv + 1);
	static const char *const subs[] = { "unwrap", "convert", "register",
					    "calibrate", NULL };
	cmd_choice_error(argv[1], subs);
	return cmd_usage_error("probe", "'%s': %s", argv[1], glint_error_msg());
}
