// Writes the fuzz targets' seed inputs that are cut from ../shared/data (tests/fuzz/make_seeds.sh
// builds and runs it; the results are kept in tests/fuzz/corpus/). Only public-domain or CC0
// sources: Poly Haven's quarry_01 (CC0), the pano.mp4 clip's first frame (three.js examples,
// MIT repository), Keenan Crane's spot (public domain). Usage: make_seeds DATA_DIR CORPUS_DIR
#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

namespace {

void put(const std::string& path, std::uint8_t first, const std::vector<std::uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.put(char(first));
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

std::vector<std::uint8_t> encode(const std::string& ext, const cv::Mat& m) {
  std::vector<std::uint8_t> out;
  if (!cv::imencode(ext, m, out)) throw std::runtime_error("cannot encode " + ext);
  return out;
}

// A camera_frame input: fourcc index, width-1, height-1, stride/2, log2(reduce), then the bytes.
void putFrame(const std::string& path, int fourcc, int w, int h, int stride, int reduceLog2,
              const std::vector<std::uint8_t>& bytes) {
  std::vector<std::uint8_t> all = {std::uint8_t(w - 1), std::uint8_t(h - 1),
                                   std::uint8_t(stride / 2), std::uint8_t(reduceLog2)};
  all.insert(all.end(), bytes.begin(), bytes.end());
  put(path, std::uint8_t(fourcc), all);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_seeds DATA_DIR CORPUS_DIR\n");
    return 2;
  }
  const std::string data = argv[1], out = argv[2];
  // image: a real HDR cut to 16x8, in each format the reader takes.
  cv::Mat hdr = cv::imread(data + "/equirect/quarry_01_1k.hdr", cv::IMREAD_UNCHANGED), small;
  cv::resize(hdr, small, {16, 8}, 0, 0, cv::INTER_AREA);
  cv::Mat ldr, ldr16;
  small.convertTo(ldr, CV_8UC3, 255.0);
  small.convertTo(ldr16, CV_16UC3, 65535.0);
  put(out + "/image/quarry-16x8.hdr", 0, encode(".hdr", small));
  put(out + "/image/quarry-16x8.png", 1, encode(".png", ldr));
  put(out + "/image/quarry-16x8-16bit.png", 1, encode(".png", ldr16));
  put(out + "/image/quarry-16x8.exr", 2, encode(".exr", small));
  put(out + "/image/quarry-16x8.jpg", 3, encode(".jpg", ldr));
  // camera_frame: the 360 clip's first frame cut to 32x16, as each camera format carries it.
  cv::VideoCapture cap(data + "/video/pano.mp4");
  cv::Mat frame, bgr;
  cap.read(frame);
  cv::resize(frame, bgr, {32, 16}, 0, 0, cv::INTER_AREA);
  putFrame(out + "/camera_frame/mjpeg-32x16", 0, 32, 16, 0, 0, encode(".jpg", bgr));
  putFrame(out + "/camera_frame/mjpeg-32x16-reduce2", 0, 32, 16, 0, 1, encode(".jpg", bgr));
  cv::Mat rgb, i420;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  putFrame(out + "/camera_frame/rgb24-32x16", 4, 32, 16, 96, 0,
           std::vector<std::uint8_t>(rgb.datastart, rgb.dataend));
  cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);  // Y plane, then U, then V (quarter each)
  const std::uint8_t* y = i420.data;
  const std::uint8_t* u = y + 32 * 16;
  const std::uint8_t* v = u + 16 * 8;
  std::vector<std::uint8_t> nv12(y, y + 32 * 16), yuyv;
  for (int i = 0; i < 16 * 8; ++i) nv12.insert(nv12.end(), {u[i], v[i]});
  for (int r = 0; r < 16; ++r)
    for (int c = 0; c < 32; c += 2) {
      const int k = (r / 2) * 16 + c / 2;
      yuyv.insert(yuyv.end(), {y[r * 32 + c], u[k], y[r * 32 + c + 1], v[k]});
    }
  putFrame(out + "/camera_frame/nv12-32x16", 3, 32, 16, 32, 0, nv12);
  putFrame(out + "/camera_frame/yuyv-32x16", 2, 32, 16, 64, 0, yuyv);
  // model: spot's first 24 triangles and their vertices, renumbered.
  std::ifstream spot(data + "/models/spot.obj");
  std::vector<std::string> vertices;
  std::vector<std::array<int, 3>> faces;
  for (std::string line; std::getline(spot, line);) {
    std::array<int, 3> f{};
    if (line.rfind("v ", 0) == 0)
      vertices.push_back(line);
    else if (faces.size() < 24 &&
             std::sscanf(line.c_str(), "f %d%*[^ ] %d%*[^ ] %d", &f[0], &f[1], &f[2]) == 3)
      faces.push_back(f);
  }
  std::map<int, int> renumber;
  std::ofstream obj(out + "/model/spot-cut.obj");
  obj << "# 24 triangles of Keenan Crane's spot (public domain)\n";
  for (auto& f : faces)
    for (int& i : f) {
      auto [it, added] = renumber.emplace(i, int(renumber.size()) + 1);
      if (added) obj << vertices.at(std::size_t(i - 1)) << "\n";
      i = it->second;
    }
  for (const auto& f : faces) obj << "f " << f[0] << " " << f[1] << " " << f[2] << "\n";
  std::printf("seeds written to %s (model: %zu vertices, %zu faces)\n", out.c_str(),
              renumber.size(), faces.size());
  return 0;
}
