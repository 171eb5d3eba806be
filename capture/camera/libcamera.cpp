// SPDX-License-Identifier: MIT
// The libcamera backend (libcamera 0.0.3, C++17), behind the C camera ops
// table.  Exceptions and C++ types never cross into C.
//
// Device string: a libcamera camera id, or empty for the first camera.
// Stream: the Raw role when the pipeline offers it (unpacked or CSI-2
// packed Bayer), else StillCapture in a format glint reads.
//
// How an applied exposure is confirmed: every completed request carries
// metadata with the ExposureTime and AnalogueGain the sensor actually used
// for that frame; the frame is labelled with those, so
// glint_camera_capture() drops frames until they equal the request.
//
// libcamera logs to stderr by default; glint silences it below ERROR
// unless glint_camera_set_verbose(1) (`--verbose`) was called first.
extern "C" {
#include "capture/camera/camera.h"
#include "core/error.h"
#include "capture/camera/v4l2_format.h"
}

#include <libcamera/libcamera.h>
#include <libcamera/logging.h>

#include <sys/mman.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

using namespace libcamera;

namespace
{

// One CameraManager per process (libcamera allows no more).
std::unique_ptr<CameraManager> g_manager;
int g_manager_users;

int manager_get()
{
	if (g_manager) {
		g_manager_users++;
		return 0;
	}
	// Below ERROR unless --verbose; the logger reads this when it is
	// first used, which is the manager's construction.  A user's own
	// LIBCAMERA_LOG_LEVELS wins.
	if (!glint_camera_verbose())
		setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
	g_manager = std::make_unique<CameraManager>();
	int ret = g_manager->start();
	if (ret < 0) {
		g_manager.reset();
		return glint_error_set(-ret,
				       "libcamera: camera manager did not "
				       "start: %s",
				       strerror(-ret));
	}
	g_manager_users = 1;
	return 0;
}

void manager_put()
{
	if (--g_manager_users == 0) {
		g_manager->stop();
		g_manager.reset();
	}
}

// libcamera's format names to V4L2's (what v4l2_format.c reads).
const glint_v4l2_format *map_format(const PixelFormat &pf)
{
	std::string n = pf.toString();
	const std::string packed = "_CSI2P";
	if (n.size() > packed.size() &&
	    n.compare(n.size() - packed.size(), packed.size(), packed) == 0)
		n = n.substr(0, n.size() - packed.size()) + "P";
	else if (n == "R8")
		n = "GREY";
	else if (n == "R16")
		n = "Y16";
	else if (n == "BGR888") // DRM order: bytes R, G, B
		n = "RGB24";
	return glint_v4l2_format_by_name(n.c_str());
}

struct Mapping {
	void *addr = nullptr;
	size_t len = 0;
	size_t offset = 0;
};

struct LcCam {
	std::shared_ptr<Camera> camera;
	std::unique_ptr<CameraConfiguration> config;
	std::unique_ptr<FrameBufferAllocator> allocator;
	std::vector<std::unique_ptr<Request>> requests;
	std::vector<Mapping> maps; // per request
	Stream *stream = nullptr;
	const glint_v4l2_format *fmt = nullptr;
	int width = 0, height = 0;
	size_t stride = 0;
	bool started = false;
	std::mutex mu;
	std::condition_variable cv;
	std::deque<Request *> done;
	bool have_exposure = false;
	bool manager_held = false;
	int32_t want_us = 0;
	float want_gain = 1;
	double period_s = 1.0 / 30;
	glint_camera_info info{};

	void completed(Request *r)
	{
		std::lock_guard<std::mutex> lk(mu);
		done.push_back(r);
		cv.notify_one();
	}
};

int fail_open(const char *what, int err)
{
	return glint_error_set(err, "libcamera: %s", what);
}

int lc_open_impl(const char *device, LcCam *c)
{
	int ret = manager_get();
	if (ret < 0)
		return ret;
	c->manager_held = true;
	auto cams = g_manager->cameras();
	if (cams.empty())
		return glint_error_set(ENODEV, "libcamera: no camera found");
	if (device && *device) {
		c->camera = g_manager->get(device);
		if (!c->camera) {
			std::string ids;
			for (auto &k : cams)
				ids += (ids.empty() ? "" : ", ") + k->id();
			return glint_error_set(ENODEV,
					       "libcamera: no camera '%s' "
					       "(found: %s)",
					       device, ids.c_str());
		}
	} else {
		c->camera = cams[0];
	}
	if (c->camera->acquire() < 0)
		return glint_error_set(EBUSY,
				       "libcamera: camera %s is in use by "
				       "another program",
				       c->camera->id().c_str());
	return 0;
}

int lc_configure_impl(LcCam *c)
{
	for (StreamRole role : { StreamRole::Raw, StreamRole::StillCapture }) {
		c->config = c->camera->generateConfiguration({ role });
		if (!c->config || c->config->empty())
			continue;
		if (c->config->validate() == CameraConfiguration::Invalid)
			continue;
		c->fmt = map_format(c->config->at(0).pixelFormat);
		if (!c->fmt) {
			// Try a format glint reads among those offered.
			StreamConfiguration &sc = c->config->at(0);
			for (const PixelFormat &pf :
			     sc.formats().pixelformats())
				if (map_format(pf)) {
					sc.pixelFormat = pf;
					break;
				}
			if (c->config->validate() ==
			    CameraConfiguration::Invalid)
				continue;
			c->fmt = map_format(sc.pixelFormat);
		}
		if (c->fmt)
			break;
	}
	if (!c->fmt)
		return glint_error_set(ENOTSUP,
				       "libcamera: camera %s offers no raw or "
				       "still format glint reads",
				       c->camera->id().c_str());
	if (c->camera->configure(c->config.get()) < 0)
		return fail_open("configure failed", EIO);
	StreamConfiguration &sc = c->config->at(0);
	c->stream = sc.stream();
	c->width = (int)sc.size.width;
	c->height = (int)sc.size.height;
	c->stride =
		sc.stride ? sc.stride : glint_v4l2_row_bytes(c->fmt, c->width);
	c->allocator = std::make_unique<FrameBufferAllocator>(c->camera);
	if (c->allocator->allocate(c->stream) < 0)
		return fail_open("buffer allocation failed", ENOMEM);
	for (const auto &buf : c->allocator->buffers(c->stream)) {
		std::unique_ptr<Request> r =
			c->camera->createRequest((uint64_t)c->requests.size());
		if (!r || r->addBuffer(c->stream, buf.get()) < 0)
			return fail_open("request creation failed", ENOMEM);
		const FrameBuffer::Plane &p = buf->planes()[0];
		Mapping m;
		m.offset = p.offset;
		m.len = p.offset + p.length;
		m.addr = mmap(nullptr, m.len, PROT_READ, MAP_SHARED, p.fd.get(),
			      0);
		if (m.addr == MAP_FAILED)
			return fail_open("mmap of a frame buffer failed",
					 errno);
		c->maps.push_back(m);
		c->requests.push_back(std::move(r));
	}
	c->camera->requestCompleted.connect(c, &LcCam::completed);

	// Describe.
	glint_camera_info &in = c->info;
	snprintf(in.backend, sizeof(in.backend), "libcamera");
	auto model = c->camera->properties().get(properties::Model);
	snprintf(in.name, sizeof(in.name), "%s",
		 model ? model->c_str() : c->camera->id().c_str());
	snprintf(in.detail, sizeof(in.detail), "%s", c->camera->id().c_str());
	in.width = c->width;
	in.height = c->height;
	for (const PixelFormat &pf : sc.formats().pixelformats()) {
		if (in.nformats >= GLINT_CAMERA_MAX_FORMATS)
			break;
		snprintf(in.formats[in.nformats++], sizeof(in.formats[0]), "%s",
			 pf.toString().c_str());
	}
	in.bit_depth = c->fmt->bits;
	const ControlInfoMap &ci = c->camera->controls();
	auto e = ci.find(&controls::ExposureTime);
	c->have_exposure = e != ci.end();
	in.manual_exposure = c->have_exposure;
	if (c->have_exposure) {
		in.exposure_min_s =
			std::max(e->second.min().get<int32_t>(), 1) * 1e-6;
		in.exposure_max_s = e->second.max().get<int32_t>() * 1e-6;
		// Sensors round to whole lines (~10-50 us); metadata
		// says what they did.
		in.exposure_step_s = 50e-6;
		snprintf(in.exposure_control, sizeof(in.exposure_control),
			 "ExposureTime (us)");
	} else {
		snprintf(in.exposure_control, sizeof(in.exposure_control),
			 "none");
	}
	auto g = ci.find(&controls::AnalogueGain);
	if (g != ci.end()) {
		in.gain_min = g->second.min().get<float>();
		in.gain_max = g->second.max().get<float>();
		in.gain_step = 1.0 / 16; // typical gain code resolution
		snprintf(in.gain_control, sizeof(in.gain_control),
			 "AnalogueGain");
	} else {
		in.gain_min = in.gain_max = 1;
		snprintf(in.gain_control, sizeof(in.gain_control), "none");
	}
	auto fd = ci.find(&controls::FrameDurationLimits);
	if (fd != ci.end())
		c->period_s = fd->second.min().get<int64_t>() * 1e-6;
	in.frame_period_min_s = c->period_s;
	// Controls ride on requests: a value lands once the requests queued
	// before it have completed.
	in.latency_frames = (int)c->requests.size();
	return 0;
}

void set_controls(LcCam *c, Request *r)
{
	ControlList &cl = r->controls();
	if (!c->have_exposure)
		return; // frames as the camera makes them (vimc: no controls)
	cl.set(controls::AeEnable, false);
	cl.set(controls::ExposureTime, c->want_us);
	if (c->info.gain_max > c->info.gain_min)
		cl.set(controls::AnalogueGain, c->want_gain);
}

} // namespace

extern "C" {

static void lc_close(void *priv)
{
	LcCam *c = static_cast<LcCam *>(priv);
	if (!c)
		return;
	if (c->started)
		c->camera->stop();
	if (c->camera)
		c->camera->requestCompleted.disconnect(c);
	for (Mapping &m : c->maps)
		munmap(m.addr, m.len);
	c->requests.clear();
	c->allocator.reset();
	bool held = c->manager_held;
	if (c->camera) {
		c->camera->release();
		c->camera.reset();
	}
	delete c;
	if (held)
		manager_put();
}

static int lc_open(const char *device, const struct glint_clock *clock,
		   void **priv)
{
	(void)clock; // libcamera paces frames itself
	*priv = nullptr;
	LcCam *c = new (std::nothrow) LcCam;
	if (!c)
		return glint_error_set(ENOMEM, "out of memory");
	int ret;
	try {
		ret = lc_open_impl(device, c);
	} catch (const std::exception &ex) {
		ret = glint_error_set(EIO, "libcamera: %s", ex.what());
	}
	if (ret < 0) {
		lc_close(c);
		return ret;
	}
	*priv = c;
	return 0;
}

static int lc_configure(void *priv)
{
	try {
		return lc_configure_impl(static_cast<LcCam *>(priv));
	} catch (const std::exception &ex) {
		return glint_error_set(EIO, "libcamera: %s", ex.what());
	}
}

static int lc_describe(void *priv, struct glint_camera_info *info)
{
	*info = static_cast<LcCam *>(priv)->info;
	return 0;
}

static int start_streaming(LcCam *c);

static int lc_set_exposure(void *priv, double *exposure_s, double *gain)
{
	LcCam *c = static_cast<LcCam *>(priv);
	if (!c->have_exposure)
		return glint_error_set(ENOTSUP,
				       "libcamera: camera %s has no "
				       "ExposureTime control",
				       c->camera->id().c_str());
	c->want_us = (int32_t)std::lround(*exposure_s * 1e6);
	c->want_gain = (float)*gain;
	*exposure_s = c->want_us * 1e-6; // the sensor may round further:
	*gain = c->want_gain;		 // its metadata will say
	return start_streaming(c);
}

// Start the camera with every request queued (with the wanted exposure
// when the camera has the control).
static int start_streaming(LcCam *c)
{
	if (!c->started) {
		ControlList start(controls::controls);
		if (c->have_exposure)
			start.set(controls::AeEnable, false);
		if (c->camera->start(&start) < 0)
			return glint_error_set(EIO,
					       "libcamera: camera %s did "
					       "not start",
					       c->camera->id().c_str());
		c->started = true;
		for (auto &r : c->requests) {
			set_controls(c, r.get());
			if (c->camera->queueRequest(r.get()) < 0)
				return glint_error_set(EIO,
						       "libcamera: queueing a "
						       "request failed");
		}
	}
	return 0;
}

static int lc_grab(void *priv, struct glint_frame *f)
{
	LcCam *c = static_cast<LcCam *>(priv);
	std::memset(f, 0, sizeof(*f));
	if (!c->started && c->have_exposure) {
		double e = c->info.exposure_min_s * 100, g = 1;
		int ret = lc_set_exposure(priv, &e, &g);
		if (ret < 0)
			return ret;
	} else if (!c->started) {
		int ret = start_streaming(c);
		if (ret < 0)
			return ret;
	}
	double timeout = std::max(2.0, 3 * c->want_us * 1e-6 + 1);
	Request *r = nullptr;
	{
		std::unique_lock<std::mutex> lk(c->mu);
		if (!c->cv.wait_for(lk, std::chrono::duration<double>(timeout),
				    [c] { return !c->done.empty(); }))
			return glint_error_set(ETIMEDOUT,
					       "libcamera: camera %s: no frame "
					       "within %.1f s",
					       c->camera->id().c_str(),
					       timeout);
		r = c->done.front();
		c->done.pop_front();
	}
	int ret = 0;
	if (r->status() == Request::RequestCancelled) {
		ret = glint_error_set(ENODEV,
				      "libcamera: camera %s stopped delivering "
				      "frames (request cancelled)",
				      c->camera->id().c_str());
	} else {
		const ControlList &md = r->metadata();
		auto e = md.get(controls::ExposureTime);
		auto g = md.get(controls::AnalogueGain);
		auto ts = md.get(controls::SensorTimestamp);
		f->exposure_s = e ? *e * 1e-6 : 0;
		f->gain = g ? *g : 1;
		FrameBuffer *fb = r->findBuffer(c->stream);
		const Mapping &m = c->maps[r->cookie()];
		size_t n = (size_t)c->width * c->height * c->fmt->channels;
		f->data = static_cast<uint16_t *>(malloc(n * sizeof(uint16_t)));
		if (!f->data)
			ret = glint_error_set(ENOMEM, "out of memory");
		else
			ret = glint_v4l2_convert(
				c->fmt,
				static_cast<uint8_t *>(m.addr) + m.offset,
				fb->metadata().planes()[0].bytesused, c->stride,
				c->width, c->height, f->data);
		f->sequence = fb->metadata().sequence;
		f->t_end = ts ? *ts * 1e-9 : 0;
		f->t_start = f->t_end - f->exposure_s;
	}
	r->reuse(Request::ReuseBuffers);
	set_controls(c, r);
	if (c->camera->queueRequest(r) < 0 && ret == 0)
		ret = glint_error_set(EIO, "libcamera: requeueing failed");
	if (ret < 0) {
		glint_frame_release(f);
		return ret;
	}
	glint_v4l2_frame_describe(c->fmt, c->width, c->height, f);
	return 0;
}

static int lc_enumerate(void (*found)(const char *device, void *ctx), void *ctx)
{
	int ret = manager_get();
	if (ret < 0)
		return ret;
	int n = 0;
	for (auto &k : g_manager->cameras()) {
		found(k->id().c_str(), ctx);
		n++;
	}
	manager_put();
	return n;
}

const struct glint_camera_ops
	glint_camera_libcamera_ops = {
		"libcamera",  lc_open,	       lc_close, lc_describe,
		lc_configure, lc_set_exposure, lc_grab,	 lc_enumerate,
		nullptr, /* start: streaming starts with the first request */
	};
}
