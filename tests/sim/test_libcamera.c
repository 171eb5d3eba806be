/* SPDX-License-Identifier: MIT */
/*
 * The libcamera backend against whatever libcamera finds on this machine.
 * Without a camera (CI, containers) it must fail cleanly with "no camera"
 * and the test skips (77) saying so; with one, it captures a frame at a
 * requested exposure and checks the metadata-confirmed exposure.
 */
#include "cmd/backends.h"
#include "test.h"

#include "capture/camera.h"
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
