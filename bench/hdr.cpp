// SPDX-License-Identifier: MIT
// HDR benchmark: glint's response recovery and 8-bit merge against
// OpenCV's (Debian's OpenCV 4.6, a benchmark-only dependency) on the real
// Memorial Church stack, side by side in one run: time (medians), merge
// throughput, and accuracy against the published radiance map (up to
// scale); plus glint's raw (linear) merge throughput on a simulated
// bracket; a chart of time and accuracy per method in bench-out/hdr.png.
// usage: bench/hdr [ROUNDS]   (default 5)
// glint's C headers include core/atomic.h, which in C++ brings <atomic>:
// a template library that must not be included with C linkage.
#include <atomic>

extern "C" {
#include "cmd/backends.h"
#include "capture/camera/bracket.h"
#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/hdr_response.h"
#include "core/error.h"
#include "core/formats.h"
#include "core/image.h"
}

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace
{

double now()
{
	return std::chrono::duration<double>(
		       std::chrono::steady_clock::now().time_since_epoch())
		.count();
}

double median(std::vector<double> v)
{
	std::sort(v.begin(), v.end());
	return v[v.size() / 2];
}

double peak_mib()
{
	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	return ru.ru_maxrss / 1024.0;
}

// Log correlation and fraction within 10 % of a reference, up to scale.
void accuracy(const float *ours, const float *ref, size_t n, double *corr,
	      double *within10)
{
	std::vector<double> lr;
	double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
	for (size_t i = 0; i < n; i++) {
		double a = ours[i], b = ref[i];
		if (!(a > 0) || !(b > 0) || !std::isfinite(a))
			continue;
		double la = std::log(a), lb = std::log(b);
		lr.push_back(la - lb);
		sa += la;
		sb += lb;
		saa += la * la;
		sbb += lb * lb;
		sab += la * lb;
	}
	double m = (double)lr.size();
	double scale = median(lr);
	size_t ok = 0;
	for (double d : lr)
		ok += std::fabs(std::exp(d - scale) - 1) < 0.1;
	*corr = (m * sab - sa * sb) /
		std::sqrt((m * saa - sa * sa) * (m * sbb - sb * sb));
	*within10 = ok / m;
}

// Time and accuracy per method, side by side: bench-out/hdr.png
// (gnuplot, when installed).
void plot()
{
	FILE *gp = fopen("bench-out/hdr.gp", "w");
	if (!gp)
		return;
	fprintf(gp,
		"set terminal pngcairo size 1000,420 font ',10'\n"
		"set output 'bench-out/hdr.png'\n"
		"set datafile separator ','\n"
		"set style fill solid 0.7 border -1\n"
		"set boxwidth 0.6\n"
		"set xtics rotate by -20 noenhanced\n"
		"set grid ytics\n"
		"set multiplot layout 1,2 title 'Memorial Church stack: glint "
		"against OpenCV 4.6'\n"
		"set title 'time to recover the response and merge (s)'\n"
		"set yrange [0:*]\n"
		"plot 'bench-out/hdr.csv' skip 1 using 0:($2+$3):xtic(1) "
		"with boxes lc rgb '#4477aa' notitle\n"
		"set title 'pixels within 10 %% of the published map (%%)'\n"
		"set yrange [0:100]\n"
		"plot 'bench-out/hdr.csv' skip 1 using 0:($6*100):xtic(1) "
		"with boxes lc rgb '#228833' notitle\n"
		"unset multiplot\n");
	fclose(gp);
	if (system("command -v gnuplot >/dev/null 2>&1") == 0 &&
	    system("gnuplot bench-out/hdr.gp") == 0)
		printf("plot: bench-out/hdr.png\n");
}

} // namespace

int main(int argc, char **argv)
{
	glint_backends_register();
	int rounds = argc > 1 ? std::max(1, atoi(argv[1])) : 5;
	const std::string dir = GLINT_SHARED_DATA "/exposures/memorial/";
	const int n = 16;
	std::vector<uint8_t *> img(n);
	std::vector<double> times(n);
	std::vector<float> times_f(n);
	std::vector<cv::Mat> cvimg(n);
	int w = 0, h = 0;
	for (int i = 0; i < n; i++) {
		char name[64];
		snprintf(name, sizeof(name), "memorial%04d.png", 61 + i);
		if (glint_png_read_rgb8((dir + name).c_str(), &w, &h, &img[i]) <
		    0) {
			fprintf(stderr,
				"bench/hdr: %s (needs ../shared/data)\n",
				glint_error_msg());
			return 1;
		}
		times[i] = 32.0 / (1 << i);
		times_f[i] = (float)times[i];
		cv::Mat rgb(h, w, CV_8UC3, img[i]);
		cv::cvtColor(rgb, cvimg[i], cv::COLOR_RGB2BGR);
	}
	struct glint_image *ref = nullptr;
	if (glint_image_read((dir + "memorial_threejs.hdr").c_str(), &ref) <
	    0) {
		fprintf(stderr, "bench/hdr: %s\n", glint_error_msg());
		return 1;
	}
	glint_ldr_stack s = { n, w, h, (const uint8_t *const *)img.data(),
			      times.data() };
	const char *names[4] = { "glint Debevec", "OpenCV Debevec",
				 "glint Robertson", "OpenCV Robertson" };
	std::vector<double> tcal[4], tmerge[4];
	double corr[4], within[4];
	for (int r = 0; r < rounds; r++)
		for (int m = 0; m < 4; m++) {
			std::vector<float> out((size_t)w * h * 3);
			double t0 = now(), t1, t2;
			if (m == 0 || m == 2) {
				double resp[256][3];
				int it;
				if (m == 0) {
					glint_debevec_opts o;
					glint_debevec_default_opts(&o);
					glint_response_debevec(&s, &o, resp);
				} else {
					glint_response_robertson(&s, 30, 0.01,
								 resp, &it);
				}
				t1 = now();
				glint_image *rad = nullptr;
				glint_ldr_merge(&s, resp, nullptr, &rad,
						nullptr);
				t2 = now();
				std::copy(rad->data, rad->data + out.size(),
					  out.begin());
				glint_image_free(rad);
			} else {
				cv::Mat resp, hdr;
				if (m == 1)
					cv::createCalibrateDebevec()->process(
						cvimg, resp, times_f);
				else
					cv::createCalibrateRobertson()->process(
						cvimg, resp, times_f);
				t1 = now();
				if (m == 1)
					cv::createMergeDebevec()->process(
						cvimg, hdr, times_f, resp);
				else
					cv::createMergeRobertson()->process(
						cvimg, hdr, times_f, resp);
				t2 = now();
				for (int i = 0; i < w * h; i++)
					for (int c = 0; c < 3; c++)
						out[3 * i + c] =
							hdr.ptr<float>()[3 * i +
									 2 - c];
			}
			tcal[m].push_back(t1 - t0);
			tmerge[m].push_back(t2 - t1);
			if (r == 0)
				accuracy(out.data(), ref->data, out.size(),
					 &corr[m], &within[m]);
		}

	// The raw merge: a simulated 17-frame bracket at 1024 x 768.
	glint_fake_clock fc = { 0 };
	glint_clock clk = glint_clock_fake(&fc);
	glint_camera *cam = nullptr;
	glint_bracket b;
	glint_bracket_opts bo;
	glint_roi all = { 0, 0, 0, 0 };
	glint_bracket_default_opts(&bo);
	glint_camera_open("sim", "sim:width=1024,height=768", &clk, &cam);
	int braw = glint_bracket_capture(cam, &all, &bo, &clk, &b);
	glint_camera_close(cam);
	std::vector<double> traw;
	for (int r = 0; braw == 0 && r < rounds; r++) {
		glint_noise_model nm;
		glint_noise_default(&nm);
		glint_raw_hdr raw;
		double t0 = now();
		glint_hdr_merge_raw(b.frames, b.n, &nm, &raw, nullptr);
		traw.push_back(now() - t0);
		glint_raw_hdr_release(&raw);
	}

	printf("Memorial stack: %d photos %dx%d; medians of %d rounds\n\n", n,
	       w, h, rounds);
	printf("%-18s %10s %10s %12s %10s %12s %12s\n", "method", "calib s",
	       "merge s", "merge Mpx/s", "vs OpenCV", "log corr.",
	       "within 10 %");
	mkdir("bench-out", 0777);
	FILE *csv = fopen("bench-out/hdr.csv", "w");
	if (csv)
		fprintf(csv, "method,calib_s,merge_s,merge_mpx_s,log_corr,"
			     "within10\n");
	for (int m = 0; m < 4; m++) {
		double tc = median(tcal[m]), tm = median(tmerge[m]);
		double ocv = median(tcal[m | 1]) + median(tmerge[m | 1]);
		printf("%-18s %10.3f %10.3f %12.1f %10.2f %12.4f %11.1f%%\n",
		       names[m], tc, tm, w * h / tm / 1e6, (tc + tm) / ocv,
		       corr[m], 100 * within[m]);
		if (csv)
			fprintf(csv, "\"%s\",%.4f,%.4f,%.2f,%.5f,%.4f\n",
				names[m], tc, tm, w * h / tm / 1e6, corr[m],
				within[m]);
	}
	if (braw == 0) {
		double t = median(traw);
		printf("\nglint raw merge, %d frames of 1024x768 Bayer: %.3f "
		       "s, "
		       "%.1f Mpx/s output (%.1f Mpx/s of input samples)\n",
		       b.n, t, 1024 * 768 / t / 1e6,
		       b.n * 1024 * 768 / t / 1e6);
		glint_bracket_release(&b);
	}
	printf("accuracy: against memorial_threejs.hdr up to scale; 'vs "
	       "OpenCV': total time / OpenCV's for the same method\n"
	       "peak memory: %.1f MiB\n",
	       peak_mib());
	if (csv) {
		fclose(csv);
		plot();
	}
	for (auto p : img)
		free(p);
	glint_image_free(ref);
	return 0;
}
