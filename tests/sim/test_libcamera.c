/* SPDX-License-Identifier: MIT */
/*
 * The libcamera backend against whatever libcamera finds on this machine.
 * Without a camera (CI, containers) it must fail cleanly with "no camera"
 * and the test skips (77) saying so; with one, it captures a frame at a
 * requested exposure and checks the metadata-confirmed exposure; with one
 * that has no exposure control (vimc under libcamera 0.0.3, in the vm
 * suite) it checks the refusal and that frames stream and decode.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera/camera.h"
#include "core/error.h"

int main(void)
{
	glint_backends_register();
	struct glint_camera *cam = NULL;
	struct glint_camera_info in;
	struct glint_frame f;

	int ret = glint_camera_open("libcamera", NULL, NULL, &cam);
	if (ret < 0) {
		CHECK(ret == -ENODEV, "open failed with %d: %s", ret,
		      glint_error_msg());
		CHECK_MSG(glint_error_msg(), "no camera");
		if (test_failures)
			return test_result();
		printf("skip: %s\n", glint_error_msg());
		return 77;
	}
	glint_camera_describe(cam, &in);
	printf("libcamera camera: %s (%s), %dx%d, %d-bit, exposure %g..%g s\n",
	       in.name, in.detail, in.width, in.height, in.bit_depth,
	       in.exposure_min_s, in.exposure_max_s);
	if (!in.manual_exposure) {
		CHECK(glint_camera_capture(cam, 0.01, 1, 8, &f, NULL) ==
			      -ENOTSUP,
		      "a camera without ExposureTime captured");
		CHECK_MSG(glint_error_msg(), "no manual exposure");
		printf("refused: %s\n", glint_error_msg());
		/* What it can do: stream frames (vimc's colour bars), once
		 * glint's own handle has let go of the camera. */
		glint_camera_close(cam);
		cam = NULL;
		void *priv = NULL;
		CHECK(glint_camera_libcamera_ops.open(in.detail, NULL, &priv) ==
			      0,
		      "%s", glint_error_msg());
		if (priv && glint_camera_libcamera_ops.configure(priv) == 0) {
			for (int i = 0; i < 3; i++) {
				int r = glint_camera_libcamera_ops.grab(priv,
									&f);
				CHECK(r == 0, "grab %d: %s", i,
				      glint_error_msg());
				if (r)
					break;
				/* Column means across the frame: bars, not
				 * a blank or constant buffer. */
				double lo = 1e30, hi = -1e30;
				for (int b = 0; b < 8; b++) {
					double sum = 0;
					int x = (2 * b + 1) * f.width / 16;
					for (int y = 0; y < f.height; y++)
						for (int c = 0; c < f.channels;
						     c++)
							sum += f.data[((size_t)y *
									       f.width +
								       x) * f.channels +
								      c];
					sum /= f.height * f.channels;
					lo = fmin(lo, sum);
					hi = fmax(hi, sum);
				}
				printf("frame %llu: %dx%d %s, %d-bit; bar "
				       "means %.0f..%.0f\n",
				       (unsigned long long)f.sequence, f.width,
				       f.height, f.format, f.bit_depth, lo, hi);
				CHECK(f.width == in.width &&
					      f.height == in.height,
				      "frame %dx%d", f.width, f.height);
				CHECK(hi > lo + 0.25 * ((1 << f.bit_depth) - 1),
				      "a flat frame: %g..%g", lo, hi);
				glint_frame_release(&f);
			}
		}
		if (priv)
			glint_camera_libcamera_ops.close(priv);
	} else {
		double e =
			fmin(fmax(0.01, in.exposure_min_s), in.exposure_max_s);
		CHECK(glint_camera_capture(cam, e, 1, 12, &f, NULL) == 0, "%s",
		      glint_error_msg());
		if (f.data) {
			CHECK(fabs(f.exposure_s - e) <= in.exposure_step_s,
			      "metadata says %g s for %g s requested",
			      f.exposure_s, e);
			glint_frame_release(&f);
		}
	}
	glint_camera_close(cam);
	return test_result();
}
