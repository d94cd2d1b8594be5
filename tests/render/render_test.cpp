// Off-screen rendering: run logs, the video writer, and whole videos of mjcf/arm4.xml checked
// with ffprobe and by decoding frames back to pixels.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iterator>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/mujoco/load.hpp"
#include "idmpc/render/close_up.hpp"
#include "idmpc/render/frame_path.hpp"
#include "idmpc/render/framing.hpp"
#include "idmpc/render/gl_context.hpp"
#include "idmpc/render/overlay.hpp"
#include "idmpc/render/progress_printer.hpp"
#include "idmpc/render/run_log.hpp"
#include "idmpc/render/run_overlay.hpp"
#include "idmpc/render/scene_dressing.hpp"
#include "idmpc/render/video.hpp"
#include "idmpc/render/video_writer.hpp"

namespace idmpc::render {
namespace {

namespace fs = std::filesystem;

const std::string kModel = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
constexpr double kPi = 3.14159265358979323846;

// small videos keep the suite fast
constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kFps = 30;

// H.264 at its default quality and MuJoCo's lighting move colours: hue within this many degrees
constexpr double kHueTolerance = 18;
constexpr double kMinSaturation = 0.35;
constexpr double kMinValue = 0.25;

// ------------------------------------------------------------------------------- helpers

// a fresh directory under the system temp dir, removed with everything in it
class TempDir {
 public:
  TempDir() {
    std::string templ = (fs::temp_directory_path() / "idmpc_render_test_XXXXXX").string();
    if (!mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed");
    path_ = templ;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// a swing-up-like log: q0 from -pi to 0 smoothly, small motions of the other joints;
// `lag` delays the whole motion (a second run that visibly differs)
void write_log(const std::string& path, int n, double duration, double lag = 0,
               double dt = 1e-3) {
  std::ofstream out(path);
  out << std::setprecision(12) << "t";
  for (const char* p : {"q", "v", "u"}) {
    for (int i = 0; i < n; ++i) out << ',' << p << i;
  }
  out << ",residual,update_ms\n";
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    const double s = std::clamp((t - lag) / (0.8 * duration), 0.0, 1.0);
    const double smooth = s * s * (3 - 2 * s);
    out << t;
    for (int i = 0; i < n; ++i) {
      out << ',' << (i == 0 ? -kPi * (1 - smooth) : 0.2 * std::sin(kPi * smooth * (i + 1)));
    }
    for (int i = 0; i < n; ++i) out << ',' << 0.0;
    for (int i = 0; i < n; ++i) out << ',' << 20 * std::sin(kPi * t / duration) / (i + 1);
    out << ',' << 1e-3 * std::exp(-t) << ',' << 0.5 + 0.1 * std::sin(7 * t) << '\n';
  }
}

// a log holding one pose (the arm still) for `duration` seconds
void write_pose_log(const std::string& path, const std::vector<double>& q, double duration,
                    double dt = 1e-2) {
  std::ofstream out(path);
  const std::size_t n = q.size();
  out << std::setprecision(12) << "t";
  for (const char* p : {"q", "v", "u"}) {
    for (std::size_t i = 0; i < n; ++i) out << ',' << p << i;
  }
  out << ",residual,update_ms\n";
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k <= steps; ++k) {
    out << k * dt;
    for (double qi : q) out << ',' << qi;
    for (std::size_t i = 0; i < 2 * n; ++i) out << ',' << 0.0;
    out << ",1e-4,0.5\n";
  }
}

// a 4-joint log in memory: rows every dt over [0, duration], |u| from u_of(t) on joint 0
RunLog memory_log(double duration, double dt, const std::function<double(double)>& u_of) {
  RunLog log;
  log.path = "memory.csv";
  log.label = "memory";
  log.n = 4;
  log.nu = 4;
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    log.t.push_back(t);
    for (int i = 0; i < 4; ++i) log.q.push_back(0.0);
    log.u.push_back(u_of(t));
    for (int i = 1; i < 4; ++i) log.u.push_back(0.0);
    log.residual.push_back(1e-4);
    log.update_ms.push_back(0.5);
  }
  return log;
}

struct CommandResult {
  int status = -1;
  std::string out;
};

// runs a shell command, capturing stdout (binary-safe)
CommandResult run(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.out.append(buffer, n);
  const int status = pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

struct StreamInfo {
  std::string codec, pix_fmt;
  int width = 0, height = 0;
  long frames = 0;
  double duration = 0;
};

StreamInfo probe(const std::string& mp4) {
  const CommandResult r = run(
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
      "stream=codec_name,pix_fmt,width,height,nb_read_frames,duration -of json '" + mp4 + "'");
  EXPECT_EQ(r.status, 0) << "ffprobe failed on " << mp4;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json& s = j.at("streams").at(0);
  StreamInfo info;
  info.codec = s.at("codec_name").get<std::string>();
  info.pix_fmt = s.at("pix_fmt").get<std::string>();
  info.width = s.at("width").get<int>();
  info.height = s.at("height").get<int>();
  info.frames = std::stol(s.at("nb_read_frames").get<std::string>());
  info.duration = std::stod(s.at("duration").get<std::string>());
  return info;
}

// frame `index` decoded to rgb24, rows top to bottom
std::vector<unsigned char> decode_frame(const std::string& mp4, int index) {
  const CommandResult r =
      run("ffmpeg -v error -i '" + mp4 + "' -vf 'select=eq(n\\," + std::to_string(index) +
          ")' -vframes 1 -f rawvideo -pix_fmt rgb24 -");
  EXPECT_EQ(r.status, 0) << "ffmpeg could not decode frame " << index << " of " << mp4;
  return std::vector<unsigned char>(r.out.begin(), r.out.end());
}

// hue in degrees, saturation and value in [0, 1]
struct Hsv {
  double h, s, v;
};

Hsv to_hsv(double r, double g, double b) {
  const double mx = std::max({r, g, b});
  const double mn = std::min({r, g, b});
  const double c = mx - mn;
  double h = 0;
  if (c > 0) {
    if (mx == r) h = 60 * std::fmod((g - b) / c + 6, 6.0);
    else if (mx == g) h = 60 * ((b - r) / c + 2);
    else h = 60 * ((r - g) / c + 4);
  }
  return {h, mx > 0 ? c / mx : 0, mx};
}

double hue_distance(double a, double b) {
  const double d = std::fabs(a - b);
  return std::min(d, 360 - d);
}

// pixels of a saturated colour whose hue is within kHueTolerance of `hue`
long count_hue(const std::vector<unsigned char>& rgb, double hue) {
  long count = 0;
  for (std::size_t i = 0; i + 2 < rgb.size(); i += 3) {
    const Hsv p = to_hsv(rgb[i] / 255.0, rgb[i + 1] / 255.0, rgb[i + 2] / 255.0);
    if (p.s >= kMinSaturation && p.v >= kMinValue && hue_distance(p.h, hue) <= kHueTolerance) {
      ++count;
    }
  }
  return count;
}

double grey_variance(const std::vector<unsigned char>& rgb) {
  double sum = 0, sum2 = 0;
  const double n = static_cast<double>(rgb.size() / 3);
  for (std::size_t i = 0; i + 2 < rgb.size(); i += 3) {
    const double y = 0.299 * rgb[i] + 0.587 * rgb[i + 1] + 0.114 * rgb[i + 2];
    sum += y;
    sum2 += y * y;
  }
  return sum2 / n - (sum / n) * (sum / n);
}

// colour of the arm's links: the box geoms of moving bodies (material colour if they have one)
Hsv link_colour(const mjModel* m) {
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] != mjGEOM_BOX || m->body_weldid[m->geom_bodyid[g]] == 0) continue;
    const int mat = m->geom_matid[g];
    const float* rgba = mat >= 0 ? m->mat_rgba + 4 * mat : m->geom_rgba + 4 * g;
    return to_hsv(rgba[0], rgba[1], rgba[2]);
  }
  throw std::runtime_error("no link box in the model");
}

VideoOptions small_options() {
  VideoOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.fps = kFps;
  return o;
}

template <class E>
std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong exception type: ") + e.what();
  }
  return "no exception";
}

class RenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(kModel)) << "missing model " << kModel;
    ASSERT_FALSE(find_on_path("ffmpeg").empty()) << "ffmpeg is not installed";
    ASSERT_FALSE(find_on_path("ffprobe").empty()) << "ffprobe is not installed";
  }
  TempDir dir_;
};

// ------------------------------------------------------------------------------- run logs

// a run summary as `idmpc swingup --summary` writes it
std::string summary_json(const char* formulation, const char* derivatives, int N, int kmax,
                         const std::string& csv) {
  // the summary of the run that wrote `csv`: its joints and steps (one row per step)
  std::ifstream in(csv);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  RunSummary s;
  s.steps = lines - 1;
  s.task = paper_task();
  s.task.formulation = formulation;
  s.task.derivatives = derivatives;
  s.task.N = N;
  s.task.kmax = kmax;
  s.n = 4;
  return to_json(s).dump();
}

TEST_F(RenderTest, ReadsLogAndLabelFromSummary) {
  const std::string csv = dir_.file("run.csv");
  write_log(csv, 4, 0.1);
  RunLog plain = read_run_log(csv);
  EXPECT_EQ(plain.n, 4);
  EXPECT_EQ(plain.nu, 4);
  EXPECT_EQ(plain.rows(), 101u);
  EXPECT_NEAR(plain.q_row(0)[0], -kPi, 1e-9);
  EXPECT_EQ(plain.label, "run");
  EXPECT_EQ(plain.nearest_row(0.0504), 50u);
  EXPECT_EQ(plain.nearest_row(-1.0), 0u);
  EXPECT_EQ(plain.nearest_row(9.0), 100u);

  std::ofstream(dir_.file("run.json")) << summary_json("id", "adjoint", 25, 10, csv);
  const RunLog labelled = read_run_log(csv);
  EXPECT_EQ(labelled.label, "C/GMRES (ID, adjoint) N=25 kmax=10");
  EXPECT_EQ(labelled.formulation, "id");
}

TEST_F(RenderTest, LogErrorsNameTheFileAndLine) {
  const std::string missing = dir_.file("missing_run.csv");
  EXPECT_NE(message_of<std::runtime_error>([&] { read_run_log(missing); }).find("missing_run.csv"),
            std::string::npos);

  const std::string header = dir_.file("bad_header.csv");
  std::ofstream(header) << "time,q0,v0,u0,residual,update_ms\n0,0,0,0,0,0\n";
  const std::string header_msg = message_of<std::runtime_error>([&] { read_run_log(header); });
  EXPECT_NE(header_msg.find("bad_header.csv"), std::string::npos) << header_msg;
  EXPECT_NE(header_msg.find("header"), std::string::npos) << header_msg;

  const std::string columns = dir_.file("short_row.csv");
  std::ofstream(columns) << "t,q0,v0,u0,residual,update_ms\n0,0,0,0,0,0\n0.001,0,0,0,0\n";
  const std::string columns_msg = message_of<std::runtime_error>([&] { read_run_log(columns); });
  EXPECT_NE(columns_msg.find("short_row.csv"), std::string::npos) << columns_msg;
  EXPECT_NE(columns_msg.find("line 3"), std::string::npos) << columns_msg;

  const std::string text = dir_.file("text_value.csv");
  std::ofstream(text) << "t,q0,v0,u0,residual,update_ms\n0,0,0,0,0,0\n0.001,abc,0,0,0,0\n";
  const std::string text_msg = message_of<std::runtime_error>([&] { read_run_log(text); });
  EXPECT_NE(text_msg.find("line 3"), std::string::npos) << text_msg;
  EXPECT_NE(text_msg.find("'q0'"), std::string::npos) << text_msg;
  EXPECT_NE(text_msg.find("'abc'"), std::string::npos) << text_msg;
}

TEST_F(RenderTest, LogWithWrongJointCountIsRejected) {
  const std::string csv = dir_.file("three_joints.csv");
  write_log(csv, 3, 0.2);
  const RunLog log = read_run_log(csv);
  const std::string out = dir_.file("never.mp4");
  const std::string msg = message_of<std::invalid_argument>(
      [&] { render_video(kModel, {log}, small_options(), out); });
  EXPECT_NE(msg.find("three_joints.csv"), std::string::npos) << msg;
  EXPECT_NE(msg.find("arm4.xml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("3 joints"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));
}

// a log whose summary says it ran on another model is refused, naming both models; one of the
// same model (the same bytes under another name) is rendered
TEST_F(RenderTest, LogOfAnotherModelIsRefused) {
  const std::string csv = dir_.file("run.csv");
  write_log(csv, 4, 0.1);
  const std::string other = dir_.file("other_arm.xml");
  {
    std::ifstream in(kModel);
    std::ofstream(other) << in.rdbuf() << "<!-- another model -->\n";
  }
  RunSummary s = summary_from_json(nlohmann::json::parse(summary_json("id", "adjoint", 25, 10, csv)), "run.json");
  s.task.model = other;
  s.model_hash = file_hash(other);
  std::ofstream(dir_.file("run.json")) << to_json(s).dump();
  const std::string out = dir_.file("never.mp4");
  const std::string msg = message_of<std::invalid_argument>(
      [&] { render_video(kModel, {read_run_log(csv)}, small_options(), out); });
  EXPECT_NE(msg.find("run.csv"), std::string::npos) << msg;
  EXPECT_NE(msg.find("other_arm.xml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("arm4.xml"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));

  s.model_hash = file_hash(kModel);  // the same model, copied elsewhere
  std::ofstream(dir_.file("run.json")) << to_json(s).dump();
  EXPECT_NO_THROW(check_run_log(read_run_log(csv), mj::load_model(kModel).get(), kModel));
}

// ------------------------------------------------------------------------------- errors

TEST_F(RenderTest, UnwritableOutputIsRejectedBeforeRendering) {
  const std::string csv = dir_.file("run.csv");
  write_log(csv, 4, 0.2);
  const RunLog log = read_run_log(csv);
  // tests may run as root: only a missing directory or /proc is reliably unwritable
  const std::vector<std::string> outs{"/proc/nonexistent/x.mp4", dir_.file("no/such/dir/x.mp4"),
                                      "/proc/x.mp4"};
  for (const std::string& out : outs) {
    const std::string msg = message_of<std::runtime_error>(
        [&] { render_video(kModel, {log}, small_options(), out); });
    EXPECT_NE(msg.find(out), std::string::npos) << msg;
  }
}

// a 2-row log spanning 33000 s would be 990001 frames: refused before anything is rendered
TEST_F(RenderTest, AbsurdVideoLengthIsRefusedUpFront) {
  const std::string csv = dir_.file("long.csv");
  std::ofstream(csv) << "t,q0,q1,q2,q3,v0,v1,v2,v3,u0,u1,u2,u3,residual,update_ms\n"
                     << "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"
                     << "33000,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n";
  const RunLog log = read_run_log(csv);
  const std::string out = dir_.file("long.mp4");
  VideoOptions options;  // 30 fps, 1 h of video at most: 108000 frames
  const std::string msg = message_of<std::invalid_argument>([&] {
    render_video(kModel, {log}, options, out,
                 [](double) { throw std::runtime_error("the render started"); });
  });
  EXPECT_NE(msg.find("990001 frames"), std::string::npos) << msg;
  EXPECT_NE(msg.find("108000"), std::string::npos) << msg;
  EXPECT_NE(msg.find("3600 s of video"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(video_frame_count(1.0, options), 31);
  EXPECT_THROW(video_frame_count(33000, options), std::invalid_argument);
  options.max_video_seconds = 0;
  EXPECT_THROW(check_video_options(options), std::invalid_argument);
}

TEST_F(RenderTest, BadOptionsAreRejected) {
  const std::string csv = dir_.file("run.csv");
  write_log(csv, 4, 0.2);
  const RunLog log = read_run_log(csv);
  const std::string out = dir_.file("x.mp4");
  VideoOptions odd = small_options();
  odd.width = 321;
  EXPECT_NE(message_of<std::invalid_argument>([&] { render_video(kModel, {log}, odd, out); })
                .find("--width"),
            std::string::npos);
  VideoOptions camera = small_options();
  camera.camera = "fixed:no_such_camera";
  const std::string msg =
      message_of<std::invalid_argument>([&] { render_video(kModel, {log}, camera, out); });
  EXPECT_NE(msg.find("no_such_camera"), std::string::npos) << msg;
  camera.camera = "90,-10";
  EXPECT_NE(message_of<std::invalid_argument>([&] { render_video(kModel, {log}, camera, out); })
                .find("--camera"),
            std::string::npos);
  const std::string none =
      message_of<std::invalid_argument>([&] { render_video(kModel, {}, small_options(), out); });
  EXPECT_NE(none.find("runs"), std::string::npos) << none;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderTest, WriterReportsMissingFfmpeg) {
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  setenv("PATH", dir_.path().c_str(), 1);
  const std::string msg = message_of<std::runtime_error>(
      [&] { VideoWriter writer(dir_.file("x.mp4"), kWidth, kHeight, kFps); });
  setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(msg.find("ffmpeg not found on PATH"), std::string::npos) << msg;
}

TEST_F(RenderTest, WriterReportsFfmpegFailureWithItsStderr) {
  // a fake ffmpeg that fails at once, as a build without libx264 would
  const fs::path bin = dir_.path() / "bin";
  fs::create_directory(bin);
  std::ofstream(bin / "ffmpeg") << "#!/bin/sh\necho \"Unknown encoder 'libx264'\" >&2\nexit 3\n";
  fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  setenv("PATH", (bin.string() + ":" + saved).c_str(), 1);
  const std::string out = dir_.file("failed.mp4");
  const std::string msg = message_of<std::runtime_error>([&] {
    VideoWriter writer(out, kWidth, kHeight, kFps);
    std::vector<unsigned char> grey(static_cast<std::size_t>(kWidth * kHeight * 3), 128);
    for (int i = 0; i < 5; ++i) writer.write_frame(grey.data());
    writer.finish();
  });
  setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(msg.find("exit status 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("Unknown encoder 'libx264'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("failed.mp4"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderTest, AbandonedWriterLeavesNoFile) {
  const std::string out = dir_.file("abandoned.mp4");
  {
    VideoWriter writer(out, kWidth, kHeight, kFps);
    std::vector<unsigned char> grey(static_cast<std::size_t>(kWidth * kHeight * 3), 128);
    writer.write_frame(grey.data());
  }
  EXPECT_FALSE(fs::exists(out));
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    ADD_FAILURE() << "left behind: " << entry.path();
  }
}

// writes a few grey frames and finishes
void write_grey_video(const std::string& out) {
  VideoWriter writer(out, kWidth, kHeight, kFps);
  std::vector<unsigned char> grey(static_cast<std::size_t>(kWidth * kHeight * 3), 128);
  for (int i = 0; i < 3; ++i) writer.write_frame(grey.data());
  writer.finish();
}

bool is_mp4(const std::string& bytes) { return bytes.size() > 8 && bytes.compare(4, 4, "ftyp") == 0; }

std::string slurp_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST_F(RenderTest, WriterWritesThroughAFifo) {
  const fs::path fifo = dir_.path() / "out.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // the reader holds the FIFO open (a writer does not block), reads until the writer is done
  // and has closed it; a writer that replaced the FIFO instead never sends anything (no hang)
  const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  std::atomic<bool> done{false};
  std::string error;
  std::thread writer([&] {
    try {
      write_grey_video(fifo.string());
    } catch (const std::exception& e) {
      error = e.what();
    }
    done = true;
  });
  std::string received;
  char buffer[1 << 16];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    ::poll(&p, 1, 50);
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n > 0) received.append(buffer, static_cast<std::size_t>(n));
    else if (done && n == 0) break;
  }
  writer.join();
  ::close(fd);
  EXPECT_EQ(error, "");
  EXPECT_EQ(fs::status(fifo).type(), fs::file_type::fifo) << "the FIFO was replaced";
  EXPECT_TRUE(is_mp4(received)) << received.size() << " bytes";
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    EXPECT_EQ(entry.path().filename(), "out.fifo") << "left behind: " << entry.path();
  }
}

TEST_F(RenderTest, WriterWritesThroughACharacterDevice) {
  // a null device node in the test directory
  const fs::path null = dir_.path() / "null";
  if (::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0) GTEST_SKIP() << "cannot create a device node";
  const int fd = ::open(null.c_str(), O_WRONLY);
  if (fd < 0) GTEST_SKIP() << "device nodes do not work here (nodev)";
  ::close(fd);
  write_grey_video(null.string());
  EXPECT_EQ(fs::status(null).type(), fs::file_type::character) << "the device was replaced by a regular file";
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    EXPECT_EQ(entry.path().filename(), "null") << "left behind: " << entry.path();
  }
}

TEST_F(RenderTest, WriterFollowsALinkAndKeepsThePermissions) {
  fs::create_directory(dir_.path() / "real");
  const fs::path target = dir_.path() / "real" / "video.mp4";
  std::ofstream(target) << "old";
  fs::permissions(target, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  fs::create_symlink("real/video.mp4", dir_.path() / "link.mp4");
  write_grey_video(dir_.file("link.mp4"));
  EXPECT_TRUE(fs::is_symlink(dir_.path() / "link.mp4")) << "the link was replaced by a regular file";
  EXPECT_TRUE(is_mp4(slurp_bytes(target)));
  EXPECT_EQ(fs::status(target).permissions(), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  for (const auto& entry : fs::directory_iterator(dir_.path() / "real")) {
    EXPECT_EQ(entry.path().filename(), "video.mp4") << "left behind: " << entry.path();
  }
}

// ------------------------------------------------------------------------------- videos

TEST_F(RenderTest, GlContextRejectsBadSize) {
  EXPECT_THROW(GlContext(0, 10), std::invalid_argument);
}

TEST_F(RenderTest, SingleRunVideoHasStreamAndArm) {
  const std::string csv = dir_.file("swing.csv");
  write_log(csv, 4, 1.0);
  const std::string out = dir_.file("swing.mp4");
  std::vector<double> fractions;
  render_video(kModel, {read_run_log(csv)}, small_options(), out,
               [&](double f) { fractions.push_back(f); });

  // stream: 1 s at 30 fps, both ends shown -> 31 frames
  const StreamInfo info = probe(out);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_EQ(info.pix_fmt, "yuv420p");
  EXPECT_EQ(info.width, kWidth);
  EXPECT_EQ(info.height, kHeight);
  EXPECT_EQ(info.frames, 31);
  EXPECT_NEAR(info.duration, 1.0, 0.1);
  ASSERT_EQ(fractions.size(), 31u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);

  // a decoded frame is not blank and shows the links' colour
  mj::ModelPtr m = mj::load_model(kModel);
  const Hsv link = link_colour(m.get());
  ASSERT_GE(link.s, kMinSaturation) << "the test needs coloured links";
  for (int index : {0, 15, 30}) {
    const std::vector<unsigned char> rgb = decode_frame(out, index);
    ASSERT_EQ(rgb.size(), static_cast<std::size_t>(kWidth * kHeight * 3));
    EXPECT_GT(grey_variance(rgb), 100.0) << "frame " << index << " looks blank";
    EXPECT_GE(count_hue(rgb, link.h), 40) << "no link-coloured pixels in frame " << index;
  }
  // nothing else left in the directory
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "swing.csv" || name == "swing.mp4") << "left behind: " << name;
  }
}

TEST_F(RenderTest, CompareVideoShowsBothRunsInTheirColours) {
  const std::string a = dir_.file("fd.csv");
  const std::string b = dir_.file("id.csv");
  write_log(a, 4, 0.5);
  write_log(b, 4, 0.5, 0.15);
  std::ofstream(dir_.file("fd.json")) << summary_json("fd", "matrix", 10, 5, a);
  std::ofstream(dir_.file("id.json")) << summary_json("id", "matrix", 10, 5, b);
  const std::string out = dir_.file("compare.mp4");
  // ID given first: the colours still follow the formulation (FD blue, ID orange); no overlay,
  // whose legend has the same colours
  VideoOptions options = small_options();
  options.overlay = false;
  render_video(kModel, {read_run_log(b), read_run_log(a)}, options, out);

  const StreamInfo info = probe(out);
  EXPECT_EQ(info.frames, 16);
  EXPECT_NEAR(info.duration, 16 / kFps, 0.1);
  const std::vector<unsigned char> rgb = decode_frame(out, 8);
  ASSERT_EQ(rgb.size(), static_cast<std::size_t>(kWidth * kHeight * 3));
  const double blue = to_hsv(0.18, 0.48, 1.0).h;
  const double orange = to_hsv(1.0, 0.52, 0.08).h;
  EXPECT_GE(count_hue(rgb, blue), 40) << "no blue (FD) arm";
  EXPECT_GE(count_hue(rgb, orange), 40) << "no orange (ID) arm";
}

TEST_F(RenderTest, DivergedRunHoldsItsLastPose) {
  const std::string csv = dir_.file("diverged.csv");
  write_log(csv, 4, 0.5);
  // rows after 0.3 s become non-finite, as a diverged run logs them
  std::ifstream in(csv);
  std::string text, line;
  std::getline(in, line);
  text = line + "\n";
  while (std::getline(in, line)) {
    const double t = std::stod(line.substr(0, line.find(',')));
    if (t > 0.3) {
      text += line.substr(0, line.find(',')) + std::string(",nan,nan,nan,nan") +
              ",0,0,0,0,nan,nan,nan,nan,nan,0.5\n";
    } else {
      text += line + "\n";
    }
  }
  in.close();
  std::ofstream(csv) << text;
  const std::string out = dir_.file("diverged.mp4");
  VideoOptions options = small_options();
  options.overlay = false;  // its red "diverged" status is close to the links' orange
  render_video(kModel, {read_run_log(csv)}, options, out);
  const std::vector<unsigned char> last = decode_frame(out, 15);
  mj::ModelPtr m = mj::load_model(kModel);
  EXPECT_GE(count_hue(last, link_colour(m.get()).h), 40) << "the arm vanished after divergence";
}

// a compare video keeps static world geometry in its own colours: a green pedestal welded to
// the world and a purple target on a mocap body (MuJoCo files mocap bodies as dynamic), neither
// moved by the logs
TEST_F(RenderTest, CompareVideoLeavesStaticGeometryUntinted) {
  std::ifstream in(kModel);
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string arm = "<body name=\"link0\"";
  ASSERT_NE(xml.find(arm), std::string::npos);
  xml.insert(xml.find(arm),
             "<body name=\"pedestal\" pos=\"1.2 0 3.4\"><geom name=\"pedestal\" type=\"box\" "
             "size=\"0.4 0.4 0.4\" rgba=\"0.1 0.8 0.2 1\"/></body>\n    "
             "<body name=\"target\" mocap=\"true\" pos=\"1.2 0 6.2\"><geom name=\"target\" "
             "type=\"sphere\" size=\"0.4\" rgba=\"0.7 0.2 0.95 1\"/></body>\n    ");
  const std::string model = dir_.file("pedestal.xml");
  std::ofstream(model) << xml;

  const std::string a = dir_.file("fd.csv");
  const std::string b = dir_.file("id.csv");
  write_log(a, 4, 0.3);
  write_log(b, 4, 0.3, 0.1);
  const std::string out = dir_.file("compare.mp4");
  VideoOptions options = small_options();
  options.overlay = false;
  render_video(model, {read_run_log(a), read_run_log(b)}, options, out);
  const std::vector<unsigned char> rgb = decode_frame(out, 4);
  ASSERT_EQ(rgb.size(), static_cast<std::size_t>(kWidth * kHeight * 3));
  EXPECT_GE(count_hue(rgb, to_hsv(0.1, 0.8, 0.2).h), 40) << "the static pedestal was recoloured";
  EXPECT_GE(count_hue(rgb, to_hsv(0.7, 0.2, 0.95).h), 40) << "the mocap target was recoloured";
  EXPECT_GE(count_hue(rgb, to_hsv(0.18, 0.48, 1.0).h), 40) << "no blue (first) arm";
  EXPECT_GE(count_hue(rgb, to_hsv(1.0, 0.52, 0.08).h), 40) << "no orange (second) arm";
}

// ------------------------------------------------------------------------------- frame paths

const std::string kUr5e = IDMPC_SOURCE_DIR "/mjcf/ur5e.xml";

// the UR5e at its home keyframe, still for `duration` s, its tool point ('tip') on a vertical
// circle of `radius` m below where it starts, run `laps` times; the tool lags the target by
// a tenth of a lap
RunLog ur5e_circle_log(const mjModel* m, double duration, double radius, double laps) {
  const int key = mj_name2id(m, mjOBJ_KEY, "home");
  const int tip = mj_name2id(m, mjOBJ_SITE, "tip");
  EXPECT_GE(key, 0);
  EXPECT_GE(tip, 0);
  mj::DataPtr data = mj::make_data(m);
  std::copy(m->key_qpos + key * m->nq, m->key_qpos + (key + 1) * m->nq, data->qpos);
  mj_fwdPosition(m, data.get());
  const double* p0 = data->site_xpos + 3 * tip;
  RunLog log;
  log.path = "ur5e_circle.csv";
  log.label = "circle";
  log.n = log.nu = m->nq;
  const double dt = 1e-2;
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    log.t.push_back(t);
    log.q.insert(log.q.end(), data->qpos, data->qpos + m->nq);
    log.u.insert(log.u.end(), static_cast<std::size_t>(m->nq), 0.0);
    log.residual.push_back(1e-4);
    log.update_ms.push_back(0.5);
    // in the y-z plane through the tip, the circle's top at the tip
    auto circle = [&](std::vector<double>& out, double phase) {
      const double a = 2 * kPi * laps * std::max(phase, 0.0);
      out.insert(out.end(), {p0[0], p0[1] + radius * std::sin(a), p0[2] - radius + radius * std::cos(a)});
    };
    circle(log.frame_ref, t / duration);
    circle(log.frame, t / duration - 0.1 / laps);
  }
  return log;
}

RunLog without_frame(RunLog log) {
  log.frame.clear();
  log.frame_ref.clear();
  return log;
}

bool same_rgb(const float* rgba, const Rgb& rgb) {
  return std::fabs(rgba[0] - rgb[0]) < 1e-6f && std::fabs(rgba[1] - rgb[1]) < 1e-6f &&
         std::fabs(rgba[2] - rgb[2]) < 1e-6f;
}

// MuJoCo's abstract scene of a model, freed with it
struct TestScene {
  mjvScene scn;
  TestScene(const mjModel* m, int maxgeom) {
    mjv_defaultScene(&scn);
    mjv_makeScene(m, &scn, maxgeom);
  }
  ~TestScene() { mjv_freeScene(&scn); }
};

// the paths' geoms appended to a scene of the arm: dots and a marker in the target's colour,
// capsules of the trail up to the row; nothing for a log without frame columns
TEST_F(RenderTest, FramePathAddsItsGeomsOnlyForLogsWithFrameColumns) {
  mj::ModelPtr model = mj::load_model(kUr5e);
  const mjModel* m = model.get();
  constexpr double kRadius = 0.05, kLaps = 3, kTrail = 0.002;
  const RunLog log = ur5e_circle_log(m, 3.0, kRadius, kLaps);
  ASSERT_TRUE(has_frame_path(log));
  mj::DataPtr data = mj::make_data(m);
  mjvOption opt;
  mjv_defaultOption(&opt);
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  TestScene scene(m, m->ngeom + 2000);
  mjvScene& scn = scene.scn;
  auto arm = [&] {
    std::copy(log.q_row(0), log.q_row(0) + m->nq, data->qpos);
    mj_fwdPosition(m, data.get());
    mjv_updateScene(m, data.get(), &opt, nullptr, &cam, mjCAT_ALL, &scn);
    return scn.ngeom;
  };

  // without frame columns: no paths
  const RunLog plain = without_frame(log);
  const FramePath none(plain, kTrail);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.max_geoms(), 0);
  const int model_geoms = arm();
  none.add(scn, plain.rows() - 1, true, kToolPath);
  EXPECT_EQ(scn.ngeom, model_geoms);

  // with them: one chain of dots around the circle, though it is run three times
  const FramePath path(log, kTrail);
  ASSERT_FALSE(path.empty());
  const std::size_t dots = path.target_dots().size();
  const double circumference = 2 * kPi * kRadius;
  EXPECT_GE(dots, 8u);
  EXPECT_LE(static_cast<double>(dots), circumference / (0.75 * 4 * path.dot_radius()) + 1);
  for (const Vec3& p : path.target_dots()) {
    const double* p0 = log.frame_ref.data();  // the circle's top
    EXPECT_NEAR(std::hypot(p[1] - p0[1], p[2] - (p0[2] - kRadius)), kRadius, 1e-9);
  }
  EXPECT_LE(path.trail_points().size(), static_cast<std::size_t>(kMaxPathSegments) + 1);

  // at each row: the dots, the trail so far and the marker at the row's target
  long last_capsules = -1;
  for (const std::size_t row : {std::size_t{0}, log.rows() / 3, log.rows() - 1}) {
    SCOPED_TRACE("row " + std::to_string(row));
    const int before = arm();
    path.add(scn, row, true, kToolPath);
    ASSERT_LE(scn.ngeom - before, path.max_geoms());
    long spheres = 0, capsules = 0, markers = 0;
    for (int i = before; i < scn.ngeom; ++i) {
      const mjvGeom& g = scn.geoms[i];
      EXPECT_EQ(g.category, mjCAT_DECOR);
      EXPECT_NE(g.objtype, mjOBJ_GEOM);  // never taken for the robot's geoms
      if (g.type == mjGEOM_SPHERE && same_rgb(g.rgba, kTargetPath)) {
        ++spheres;
        if (std::fabs(g.size[0] - path.marker_radius()) < 1e-6) {
          ++markers;
          const double* target = log.frame_ref.data() + 3 * row;
          for (int k = 0; k < 3; ++k) EXPECT_NEAR(g.pos[k], target[k], 1e-5);
        }
      } else if (g.type == mjGEOM_CAPSULE && same_rgb(g.rgba, kToolPath)) {
        ++capsules;
        EXPECT_NEAR(g.size[0], kTrail, 1e-6);
      } else {
        ADD_FAILURE() << "unexpected geom of type " << g.type;
      }
    }
    EXPECT_EQ(markers, 1);
    EXPECT_EQ(spheres, static_cast<long>(dots) + 1);
    if (row == 0) {
      EXPECT_EQ(capsules, 0);  // no trail yet
    }
    EXPECT_GT(capsules, last_capsules);    // the trail grows
    last_capsules = capsules;
  }
  EXPECT_GE(last_capsules, 100);

  // another run's trail alone, in its colour
  const int before = arm();
  path.add(scn, log.rows() - 1, false, kOrange);
  for (int i = before; i < scn.ngeom; ++i) {
    EXPECT_EQ(scn.geoms[i].type, mjGEOM_CAPSULE);
    EXPECT_TRUE(same_rgb(scn.geoms[i].rgba, kOrange));
  }
  EXPECT_EQ(scn.ngeom - before, last_capsules);

  // a full scene takes what fits
  const int full = arm();
  scn.maxgeom = full + 5;
  path.add(scn, log.rows() - 1, true, kToolPath);
  EXPECT_EQ(scn.ngeom, full + 5);
}

// the video of a run with a frame target shows its paths in their colours; the same run
// without the frame columns renders as before, without them
TEST_F(RenderTest, VideoOfAFrameTargetShowsItsPaths) {
  mj::ModelPtr model = mj::load_model(kUr5e);
  const RunLog log = ur5e_circle_log(model.get(), 0.5, 0.1, 1);
  VideoOptions options = small_options();
  options.width = 480;
  options.height = 360;
  options.overlay = false;
  const std::string with = dir_.file("with.mp4");
  const std::string without = dir_.file("without.mp4");
  render_video(kUr5e, {log}, options, with);
  render_video(kUr5e, {without_frame(log)}, options, without);
  const std::vector<unsigned char> a = decode_frame(with, 12);
  const std::vector<unsigned char> b = decode_frame(without, 12);
  ASSERT_EQ(a.size(), static_cast<std::size_t>(480 * 360 * 3));
  ASSERT_EQ(a.size(), b.size());
  const double magenta = to_hsv(kTargetPath[0], kTargetPath[1], kTargetPath[2]).h;
  const double green = to_hsv(kToolPath[0], kToolPath[1], kToolPath[2]).h;
  EXPECT_GE(count_hue(a, magenta), 60) << "no target path";
  EXPECT_GE(count_hue(a, green), 30) << "no tool path";
  EXPECT_LE(count_hue(b, magenta), 5) << "a target path without frame columns";
  EXPECT_LE(count_hue(b, green), 5) << "a tool path without frame columns";
}

// a small flat path gets a close-up in the first free corner, seen square-on from the side of
// its plane away from the motion; a path a quarter of the motion or larger, or no free corner,
// gets none
TEST_F(RenderTest, CloseUpShowsASmallFlatPathSquareOnInAFreeCorner) {
  mj::ModelPtr model = mj::load_model(kUr5e);
  const RunLog log = ur5e_circle_log(model.get(), 2.0, 0.05, 1);  // in the y-z plane at the tip
  const FramePath path(log, 0.002);
  ASSERT_FALSE(path.empty());
  const Vec3 tip{log.frame_ref[0], log.frame_ref[1], log.frame_ref[2]};
  // the arm's motion: a 1 m box on the −x side of the circle
  Bounds motion;
  motion.extend(Vec3{tip[0] - 0.5, tip[1], tip[2]}.data(), Vec3{0.5, 0.5, 0.5});
  constexpr int kW = 1280, kH = 720, kMargin = 9;
  OverlayPlaces places;
  places.table = mjrRect{kMargin, kH - kMargin - 200, 300, 200};  // top left
  places.plot = mjrRect{kW - kMargin - 380, kMargin, 380, 220};   // bottom right
  const ScreenMask clear(32, 18);
  const CloseUp c = plan_close_up(path, motion, 30, -20, 45, kW, kH, places, clear, kMargin);
  ASSERT_TRUE(c.shown);
  EXPECT_EQ(c.rect.left + c.rect.width, kW - kMargin) << "top right";
  EXPECT_EQ(c.rect.bottom + c.rect.height, kH - kMargin) << "top right";
  EXPECT_EQ(c.rect.width, 384);
  EXPECT_EQ(c.rect.height, 216);
  // the plane's normal is ±x; the motion lies on −x, so the camera is on +x looking along −x
  EXPECT_NEAR(std::fabs(c.cam.azimuth), 180, 1e-6);
  EXPECT_NEAR(c.cam.elevation, 0, 1e-6);
  EXPECT_NEAR(c.cam.lookat[1], tip[1], 1e-6);
  EXPECT_NEAR(c.cam.lookat[2], tip[2] - 0.05, 1e-3) << "aimed at the circle's centre";
  EXPECT_GT(c.cam.distance, 0);
  // the motion on +x: the camera on −x looking along +x
  Bounds other_side;
  other_side.extend(Vec3{tip[0] + 0.5, tip[1], tip[2]}.data(), Vec3{0.5, 0.5, 0.5});
  const CloseUp back = plan_close_up(path, other_side, 30, -20, 45, kW, kH, places, clear, kMargin);
  ASSERT_TRUE(back.shown);
  EXPECT_NEAR(back.cam.azimuth, 0, 1e-6);

  // the robot in the top right: the next free corner (top left holds the table: bottom left)
  ScreenMask robot(32, 18);
  robot.mark(ScreenRegion{0.3, 1, 0.3, 1});
  const CloseUp moved = plan_close_up(path, motion, 30, -20, 45, kW, kH, places, robot, kMargin);
  ASSERT_TRUE(moved.shown);
  EXPECT_EQ(moved.rect.left, kMargin);
  EXPECT_EQ(moved.rect.bottom, kMargin);

  robot.mark_all();
  EXPECT_FALSE(plan_close_up(path, motion, 30, -20, 45, kW, kH, places, robot, kMargin).shown) << "no free corner";
  Bounds small;
  small.extend(tip.data(), Vec3{0.15, 0.15, 0.15});
  EXPECT_FALSE(plan_close_up(path, small, 30, -20, 45, kW, kH, places, clear, kMargin).shown)
      << "a path a third of the motion needs none";
}

// the video shows the close-up: the target's magenta dots fill the top-right corner, where
// without the overlays (and the close-up) there are hardly any
TEST_F(RenderTest, VideoOfASmallPathShowsItsCloseUp) {
  mj::ModelPtr model = mj::load_model(kUr5e);
  const RunLog log = ur5e_circle_log(model.get(), 0.5, 0.04, 1);
  VideoOptions options = small_options();
  options.width = 640;
  options.height = 360;
  const std::string with = dir_.file("close_up.mp4");
  const std::string without = dir_.file("no_close_up.mp4");
  render_video(kUr5e, {log}, options, with);
  options.overlay = false;
  render_video(kUr5e, {log}, options, without);
  const double magenta = to_hsv(kTargetPath[0], kTargetPath[1], kTargetPath[2]).h;
  // the top-right corner of a frame: kCloseUpSide of each side
  const auto corner = [](const std::vector<unsigned char>& rgb, int width, int height) {
    std::vector<unsigned char> out;
    const int w = static_cast<int>(kCloseUpSide * width), h = static_cast<int>(kCloseUpSide * height);
    for (int y = 0; y < h; ++y) {
      const auto row = rgb.begin() + (static_cast<long>(y) * width + (width - w)) * 3;
      out.insert(out.end(), row, row + 3L * w);
    }
    return out;
  };
  const long in_close_up = count_hue(corner(decode_frame(with, 12), 640, 360), magenta);
  const long plain = count_hue(corner(decode_frame(without, 12), 640, 360), magenta);
  EXPECT_GE(in_close_up, plain + 100) << "close-up " << in_close_up << ", without " << plain;
}

// --antialias renders with the model's multisampling: the edges, and so the frame, differ
TEST_F(RenderTest, AntialiasingChangesTheEdges) {
  mj::ModelPtr model = mj::load_model(kUr5e);
  const RunLog log = ur5e_circle_log(model.get(), 0.2, 0.04, 1);
  VideoOptions options = small_options();
  options.overlay = false;
  const std::string plain = dir_.file("plain.mp4"), smooth = dir_.file("smooth.mp4");
  render_video(kUr5e, {log}, options, plain);
  options.antialias = true;
  render_video(kUr5e, {log}, options, smooth);
  const std::vector<unsigned char> a = decode_frame(plain, 2), b = decode_frame(smooth, 2);
  ASSERT_EQ(a.size(), b.size());
  long differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += std::abs(int(a[i]) - int(b[i])) > 24;
  EXPECT_GE(differ, 50) << "anti-aliasing changed " << differ << " channel values";
}

// ------------------------------------------------------------------------------- overlay

// |u| with a 3 ms spike of 235 N m in 2 s at 1 ms rows: the plot at 1280 x 720 (384 pixels
// wide) must show the spike at its full height
TEST_F(RenderTest, UPlotShowsShortPeaksAtFullHeight) {
  constexpr double kSpike = 235;
  const RunLog log = memory_log(2.0, 1e-3, [](double t) {
    return (t > 0.4995 && t < 0.5025) ? kSpike : 50.0;
  });
  const auto curve = u_envelope(log, 0.0, 2.0, 384);
  ASSERT_FALSE(curve.empty());
  float peak = 0;
  for (const auto& p : curve) peak = std::max(peak, p[1]);
  EXPECT_FLOAT_EQ(peak, kSpike);
  EXPECT_LE(curve.size(), 384u);

  // the plot's value axis reaches the spike
  TimePlot plot("|u| [N m]", 0.0, 2.0, {PlotCurve{curve, {1, 1, 1}, false}});
  EXPECT_GE(plot.value_top(), kSpike);

  // a curve thinned to the plot's sample limit keeps its peak too
  std::vector<std::array<float, 2>> raw;
  for (std::size_t i = 0; i < log.rows(); ++i) {
    raw.push_back({static_cast<float>(log.t[i]), static_cast<float>(log.u_norm(i))});
  }
  TimePlot thinned("|u| [N m]", 0.0, 2.0, {PlotCurve{raw, {1, 1, 1}, false}});
  ASSERT_LE(thinned.curves()[0].points.size(), static_cast<std::size_t>(kPlotMaxSamples));
  float thinned_peak = 0;
  for (const auto& p : thinned.curves()[0].points) thinned_peak = std::max(thinned_peak, p[1]);
  EXPECT_FLOAT_EQ(thinned_peak, kSpike);
}

TEST_F(RenderTest, UEnvelopeStopsWhereTheLogTurnsNonFinite) {
  const RunLog log = memory_log(1.0, 1e-2, [](double t) {
    return t < 0.5 ? 10.0 : std::numeric_limits<double>::quiet_NaN();
  });
  const auto curve = u_envelope(log, 0.0, 1.0, 100);
  ASSERT_FALSE(curve.empty());
  EXPECT_LT(curve.back()[0], 0.5f);
  for (const auto& p : curve) EXPECT_FLOAT_EQ(p[1], 10.0f);
}

// the overlays go to the first corner the robot leaves free; the plot shrinks or goes
TEST_F(RenderTest, OverlaysAreMovedOffTheRobot) {
  constexpr int kW = 1280, kH = 720, kMargin = 9;
  const OverlayPlaces wanted{{kMargin, kH - kMargin - 170, 500, 170},
                             {kW - kMargin - 384, kMargin, 384, 200}};
  const std::array<int, 2> min_plot{240, 120};

  // nothing in the way: the preferred corners
  const ScreenMask clear(160, 90);
  const OverlayPlaces same = place_overlays(wanted, min_plot, clear, kW, kH, kMargin);
  EXPECT_EQ(same.table.left, wanted.table.left);
  EXPECT_EQ(same.table.bottom, wanted.table.bottom);
  EXPECT_EQ(same.plot.left, wanted.plot.left);
  EXPECT_EQ(same.plot.bottom, wanted.plot.bottom);

  // the robot top left and bottom right: table top right, plot bottom left
  ScreenMask robot(160, 90);
  robot.mark({-0.7, -0.5, 0.6, 0.9});
  robot.mark({0.7, 0.8, -0.8, -0.6});
  const OverlayPlaces moved = place_overlays(wanted, min_plot, robot, kW, kH, kMargin);
  EXPECT_EQ(moved.table.left, kW - kMargin - 500);
  EXPECT_EQ(moved.table.bottom, wanted.table.bottom);
  EXPECT_EQ(moved.plot.left, kMargin);
  EXPECT_EQ(moved.plot.bottom, kMargin);
  EXPECT_EQ(moved.plot.width, 384);

  // room only for a smaller plot: it shrinks
  ScreenMask crowded(160, 90);
  crowded.mark({-1, 1, -0.35, 0.45});
  crowded.mark({-0.5, -0.45, -1, 1});
  crowded.mark({0.45, 0.5, -1, 1});
  const OverlayPlaces shrunk = place_overlays(wanted, min_plot, crowded, kW, kH, kMargin);
  EXPECT_GT(shrunk.plot.width, 0);
  EXPECT_LT(shrunk.plot.width, 384);
  EXPECT_EQ(crowded.count({2.0 * shrunk.plot.left / kW - 1,
                           2.0 * (shrunk.plot.left + shrunk.plot.width) / kW - 1,
                           2.0 * shrunk.plot.bottom / kH - 1,
                           2.0 * (shrunk.plot.bottom + shrunk.plot.height) / kH - 1}),
            0);

  // no room at all: the plot goes, the table covers as little as it can
  ScreenMask full(160, 90);
  full.mark_all();
  const OverlayPlaces none = place_overlays(wanted, min_plot, full, kW, kH, kMargin);
  EXPECT_EQ(none.plot.width, 0);
  EXPECT_EQ(none.table.width, 500);
}

// with a model camera that shows the arm where the table would go, the overlay moves: every
// arm pixel of the video without overlay looks the same with it
TEST_F(RenderTest, OverlayDoesNotCoverTheArm) {
  // the arm still, leaning up and left: under the table's corner in the 'side' camera
  const std::string csv = dir_.file("lean.csv");
  write_pose_log(csv, {-kPi / 4, 0, 0, 0}, 0.1);
  // a real run's label makes the table wide enough to reach the arm's tip
  std::ofstream(dir_.file("lean.json")) << summary_json("id", "adjoint", 25, 10, csv);
  const RunLog log = read_run_log(csv);
  VideoOptions options;
  options.camera = "fixed:side";
  const std::string with = dir_.file("with.mp4");
  const std::string without = dir_.file("without.mp4");
  render_video(kModel, {log}, options, with);
  options.overlay = false;
  render_video(kModel, {log}, options, without);

  const std::vector<unsigned char> a = decode_frame(without, 2);
  const std::vector<unsigned char> b = decode_frame(with, 2);
  ASSERT_EQ(a.size(), b.size());
  mj::ModelPtr m = mj::load_model(kModel);
  const double link = link_colour(m.get()).h;
  long arm = 0, covered = 0;
  for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
    const Hsv p = to_hsv(a[i] / 255.0, a[i + 1] / 255.0, a[i + 2] / 255.0);
    if (p.s < kMinSaturation || p.v < kMinValue || hue_distance(p.h, link) > kHueTolerance) {
      continue;
    }
    ++arm;
    const int diff = std::abs(a[i] - b[i]) + std::abs(a[i + 1] - b[i + 1]) +
                     std::abs(a[i + 2] - b[i + 2]);
    if (diff > 90) ++covered;
  }
  ASSERT_GE(arm, 400) << "the test needs the arm in view";
  EXPECT_LE(covered, arm / 50) << covered << " of " << arm << " arm pixels under the overlay";
}

// ------------------------------------------------------------------------------- progress

std::string read_all(std::FILE* f) {
  std::rewind(f);
  std::string text;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0) text.append(buffer, n);
  return text;
}

// off a terminal (a file, a pipe, a CI log): ten plain lines, no carriage returns
TEST(ProgressPrinterTest, PrintsPlainLinesOffATerminal) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer("rendering x.mp4", f);
    EXPECT_FALSE(printer.terminal());
    for (int k = 1; k <= 31; ++k) printer(k / 31.0);
  }
  const std::string text = read_all(f);
  std::fclose(f);
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  std::string expected;
  for (int p = 10; p <= 100; p += 10) expected += "rendering x.mp4: " + std::to_string(p) + "%\n";
  EXPECT_EQ(text, expected);
}

// on a terminal: redrawn in place, one newline at the end (or when interrupted)
TEST(ProgressPrinterTest, RedrawsInPlaceOnATerminal) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer("rendering", f, true);
    for (int k = 1; k <= 4; ++k) printer(k / 4.0);
  }
  {
    ProgressPrinter interrupted("rendering", f, true);
    interrupted(0.5);
  }
  const std::string text = read_all(f);
  std::fclose(f);
  EXPECT_EQ(text, "\rrendering:  25%\rrendering:  50%\rrendering:  75%\rrendering: 100%\n"
                  "\rrendering:  50%\n");
}

// a real terminal is told from isatty
TEST(ProgressPrinterTest, TellsATerminal) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) {
    if (master >= 0) close(master);
    GTEST_SKIP() << "no pseudo-terminal available";
  }
  std::FILE* tty = std::fopen(ptsname(master), "w");
  ASSERT_NE(tty, nullptr);
  {
    ProgressPrinter printer("rendering", tty);
    EXPECT_TRUE(printer.terminal());
    printer(1.0);
  }
  std::fclose(tty);
  std::string text;
  pollfd p{master, POLLIN, 0};
  char buffer[256];
  while (poll(&p, 1, 200) > 0 && (p.revents & POLLIN)) {
    const ssize_t n = read(master, buffer, sizeof(buffer));
    if (n <= 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
  }
  close(master);
  EXPECT_NE(text.find("\rrendering: 100%"), std::string::npos) << text;
}

// ------------------------------------------------------------------------------- command line

// stderr to a file: plain progress lines, no carriage returns
TEST_F(RenderTest, CommandLineProgressInALogHasNoCarriageReturns) {
  const std::string csv = dir_.file("cli.csv");
  write_log(csv, 4, 0.3);
  const std::string out = dir_.file("cli.mp4");
  const std::string err = dir_.file("stderr.txt");
  const CommandResult ok = run(std::string("'") + IDMPC_BINARY + "' render '" + kModel +
                               "' --log '" + csv + "' --out '" + out +
                               "' --width 320 --height 240 2>'" + err + "'");
  ASSERT_EQ(ok.status, 0);
  std::ifstream in(err);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  EXPECT_NE(text.find("rendering " + out + ": 100%\n"), std::string::npos) << text;
}

TEST_F(RenderTest, CommandLineRendersAndReportsErrors) {
  const std::string csv = dir_.file("cli.csv");
  write_log(csv, 4, 0.3);
  const std::string out = dir_.file("cli.mp4");
  const std::string idmpc = std::string("'") + IDMPC_BINARY + "' render '" + kModel + "'";
  const CommandResult ok = run(idmpc + " --log '" + csv + "' --out '" + out +
                               "' --width 320 --height 240 --fps 20 2>/dev/null");
  EXPECT_EQ(ok.status, 0);
  ASSERT_TRUE(fs::exists(out));
  EXPECT_EQ(probe(out).frames, 7);

  const CommandResult both = run(idmpc + " --log '" + csv + "' --compare '" + csv + "' '" + csv +
                                 "' --out '" + out + "' 2>&1");
  EXPECT_NE(both.status, 0);
  const CommandResult neither = run(idmpc + " --out '" + out + "' 2>&1");
  EXPECT_EQ(neither.status, 1);
  EXPECT_NE(neither.out.find("idmpc: error:"), std::string::npos) << neither.out;
  const CommandResult unwritable =
      run(idmpc + " --log '" + csv + "' --out /proc/nonexistent/x.mp4 2>&1");
  EXPECT_EQ(unwritable.status, 1);
  EXPECT_NE(unwritable.out.find("/proc/nonexistent/x.mp4"), std::string::npos) << unwritable.out;
  const CommandResult missing =
      run(idmpc + " --log '" + dir_.file("nope.csv") + "' --out '" + out + "' 2>&1");
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.out.find("nope.csv"), std::string::npos) << missing.out;
}

// a run whose controller held the gripper's fingers logs the arm's joints; its summary says where
// the fingers were held, and the render puts them there on the whole model; without the summary
// the log does not fit the model
TEST_F(RenderTest, ALogWithHeldJointsReplaysThemWhereHeld) {
  const std::string csv = dir_.file("hand.csv");
  const std::string task = std::string(IDMPC_SOURCE_DIR) + "/mjcf/panda_hand_reach.json";
  const CommandResult ran = run(std::string("'") + IDMPC_BINARY + "' swingup --task '" + task +
                                "' --duration 0.1 --quiet --log '" + csv + "' --summary '" + dir_.file("hand.json") +
                                "' 2>&1");
  ASSERT_EQ(ran.status, 2) << "0.1 s: ran, target not reached yet\n" << ran.out;
  const std::string model = std::string(IDMPC_SOURCE_DIR) + "/mjcf/panda_hand.xml";
  const RunLog log = read_run_log(csv);
  ASSERT_EQ(log.n, 7);
  ASSERT_EQ(log.held_joints, (std::vector<std::string>{"finger_joint1", "finger_joint2"}));
  const mj::ModelPtr m = mj::load_model(model);
  check_run_log(log, m.get(), model);
  std::vector<mjtNum> qpos(static_cast<std::size_t>(m->nq), -1.0);
  log_pose(log, 5, m.get(), qpos.data());
  for (int i = 0; i < 7; ++i) EXPECT_EQ(qpos[static_cast<std::size_t>(i)], log.q_row(5)[i]) << i;
  EXPECT_EQ(qpos[7], 0.04);
  EXPECT_EQ(qpos[8], 0.04);
  const std::string out = dir_.file("hand.mp4");
  render_video(model, {log}, small_options(), out);
  EXPECT_TRUE(fs::exists(out));

  fs::remove(dir_.file("hand.json"));
  const RunLog bare = read_run_log(csv);
  const std::string msg = message_of<std::invalid_argument>([&] { check_run_log(bare, m.get(), model); });
  EXPECT_NE(msg.find("7 joints but model 'panda_hand.xml' has 9"), std::string::npos) << msg;
}

// a stale or broken summary beside the log: a warning, and the log is rendered under its name
TEST_F(RenderTest, CommandLineWarnsAboutAStaleSummaryAndRendersTheLog) {
  const std::string csv = dir_.file("cli.csv");
  write_log(csv, 4, 0.1);
  const std::string idmpc = std::string("'") + IDMPC_BINARY + "' render '" + kModel + "' --log '" + csv +
                            "' --out '" + dir_.file("cli.mp4") + "' --width 320 --height 240 2>&1 >/dev/null";
  std::ofstream(dir_.file("cli.json")) << summary_json("fd", "matrix", 50, 3, dir_.file("absent.csv"));
  const CommandResult stale = run(idmpc);
  EXPECT_EQ(stale.status, 0) << stale.out;
  EXPECT_NE(stale.out.find("idmpc: warning: run summary '" + dir_.file("cli.json") + "'"), std::string::npos) << stale.out;
  EXPECT_NE(stale.out.find("file name"), std::string::npos) << stale.out;
  EXPECT_TRUE(fs::exists(dir_.file("cli.mp4")));
  fs::remove(dir_.file("cli.mp4"));

  std::ofstream(dir_.file("cli.json")) << "{ broken";
  const CommandResult broken = run(idmpc);
  EXPECT_EQ(broken.status, 0) << broken.out;
  EXPECT_NE(broken.out.find("idmpc: warning:"), std::string::npos) << broken.out;
  EXPECT_NE(broken.out.find("cli.json"), std::string::npos) << broken.out;
  EXPECT_TRUE(fs::exists(dir_.file("cli.mp4")));
}

TEST_F(RenderTest, CommandLineRefusesAnOutputThatIsAnInput) {
  const std::string csv = dir_.file("cli.csv");
  write_log(csv, 4, 0.1);
  const std::string other = dir_.file("other.csv");
  write_log(other, 4, 0.1, 0.05);
  fs::copy_file(kModel, dir_.file("model.xml"));
  const std::string log_bytes = slurp_bytes(csv);
  const std::string idmpc = "cd '" + dir_.path().string() + "' && '" + std::string(IDMPC_BINARY) + "' render model.xml";
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {" --log cli.csv --out cli.csv", {"--out 'cli.csv'", "--log 'cli.csv'"}},
      {" --log cli.csv --out model.xml", {"--out 'model.xml'", "model 'model.xml'"}},
      {" --compare other.csv cli.csv --out cli.csv", {"--out 'cli.csv'", "--compare 'cli.csv'"}}};
  for (const auto& [args, needles] : cases) {
    const CommandResult r = run(idmpc + args + " --width 320 --height 240 2>&1");
    EXPECT_EQ(r.status, 1) << args;
    EXPECT_EQ(r.out.rfind("idmpc: error:", 0), 0u) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    for (const std::string& needle : needles) EXPECT_NE(r.out.find(needle), std::string::npos) << r.out;
  }
  EXPECT_EQ(slurp_bytes(csv), log_bytes);
  EXPECT_EQ(slurp_bytes(dir_.file("model.xml")), slurp_bytes(kModel));
}

// ffmpeg exits 0 when its writes fail (a full disk; here a file size limit with SIGXFSZ
// ignored, so writes fail with EFBIG as they would with ENOSPC): the command fails naming the
// cause, the good video already there stays byte for byte, and no temporary is left behind
TEST_F(RenderTest, CommandLineRefusesAVideoTruncatedByAFailedWrite) {
  const std::string csv = dir_.file("cli.csv");
  write_log(csv, 4, 1.0);
  const std::string out = dir_.file("v.mp4");
  const std::string idmpc = "cd '" + dir_.path().string() + "' && '" + std::string(IDMPC_BINARY) + "' render '" +
                            std::string(kModel) + "' --log cli.csv --out v.mp4 --width 320 --height 240";
  ASSERT_EQ(run(idmpc + " 2>/dev/null").status, 0);
  const std::string good = slurp_bytes(out);
  ASSERT_GT(good.size(), 8192u) << "the limit below must cut the video";
  const CommandResult r = run("bash -c \"trap '' XFSZ; ulimit -f 8; " + idmpc + " 2>&1\"");
  EXPECT_NE(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("idmpc: error: ffmpeg exited 0 but the video for 'v.mp4' is incomplete"), std::string::npos)
      << r.out;
  EXPECT_EQ(slurp_bytes(out), good);
  for (const auto& e : fs::directory_iterator(dir_.path())) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
}

}  // namespace
}  // namespace idmpc::render
