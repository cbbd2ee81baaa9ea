#include "liveprobe/capture/image.h"

#include <png.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "camera_jpeg.h"
#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/frame/frame.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"

namespace lp {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::int64_t gMaxPixels = kDefaultMaxImagePixels;

void checkPixelCount(const std::string& path, std::int64_t width, std::int64_t height) {
  if (width * height <= gMaxPixels) return;
  throw Error(path + ": " + std::to_string(width) + "x" + std::to_string(height) + " is " +
              std::to_string(width * height / 1000000) + " M pixels, above the limit of " +
              std::to_string(gMaxPixels / 1000000) + " M (LIVEPROBE_MAX_PIXELS raises it)");
}

// The frame size an OpenEXR file's header declares (its first part's dataWindow attribute, a
// box2i: xMin, yMin, xMax, yMax), read before any decoding; none where the header does not say
// it within `n` bytes. Layout per the OpenEXR file format: magic, version, then attributes (name,
// type, int32 size, value) up to an empty name.
std::optional<std::pair<std::int64_t, std::int64_t>> exrDataWindow(const std::uint8_t* p,
                                                                   std::size_t n) {
  auto int32At = [&](std::size_t at) {
    return std::int32_t(std::uint32_t(p[at]) | std::uint32_t(p[at + 1]) << 8 |
                        std::uint32_t(p[at + 2]) << 16 | std::uint32_t(p[at + 3]) << 24);
  };
  std::size_t i = 8;
  auto text = [&](std::string& out) {
    const auto* end = static_cast<const std::uint8_t*>(std::memchr(p + i, 0, n - std::min(i, n)));
    if (i >= n || !end) return false;
    out.assign(reinterpret_cast<const char*>(p + i), std::size_t(end - (p + i)));
    i = std::size_t(end - p) + 1;
    return true;
  };
  for (std::string name, type; text(name) && !name.empty() && text(type);) {
    if (i + 4 > n) return std::nullopt;
    const std::int32_t size = int32At(i);
    i += 4;
    if (size < 0 || std::size_t(size) > n - i) return std::nullopt;
    if (name == "dataWindow" && type == "box2i" && size == 16)
      return std::pair<std::int64_t, std::int64_t>{
          std::int64_t(int32At(i + 8)) - int32At(i) + 1,
          std::int64_t(int32At(i + 12)) - int32At(i + 4) + 1};
    i += std::size_t(size);
  }
  return std::nullopt;
}

// A JPEG's or an OpenEXR file's frame size, from its header, held to the pixel limit before
// OpenCV decodes it. (OpenCV's own limit, OPENCV_IO_MAX_IMAGE_PIXELS, is read when its library
// loads, before liveprobe can set it: a few hundred bytes could otherwise ask for gigabytes.) A
// header that does not say its size where the format puts it is refused as corrupt: libjpeg
// would skip stray bytes to find a frame header the strict reading does not see. The header is
// read in growing pieces (metadata segments come first), up to 64 MB.
void checkHeaderSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> head;
  enum class Kind { Other, Jpeg, Exr } kind = Kind::Other;
  for (std::size_t want = 1 << 16;; want *= 4) {
    const std::size_t had = head.size();
    head.resize(want);
    in.read(reinterpret_cast<char*>(head.data() + had), std::streamsize(want - had));
    head.resize(had + std::size_t(in.gcount()));
    const std::uint8_t* p = head.data();
    const std::size_t n = head.size();
    if (had == 0)
      kind = n >= 4 && p[0] == 0xFF && p[1] == 0xD8                                   ? Kind::Jpeg
             : n >= 8 && p[0] == 0x76 && p[1] == 0x2F && p[2] == 0x31 && p[3] == 0x01 ? Kind::Exr
                                                                                      : Kind::Other;
    if (kind == Kind::Other) return;
    std::optional<std::pair<std::int64_t, std::int64_t>> size;
    if (kind == Kind::Jpeg) {
      if (const auto s = jpegFrameSize(p, n)) size = {s->first, s->second};
    } else {
      size = exrDataWindow(p, n);
    }
    if (size) {
      if (size->first <= 0 || size->second <= 0)
        throw Error(path + ": the header declares an empty image (" + std::to_string(size->first) +
                    "x" + std::to_string(size->second) + ")");
      return checkPixelCount(path, size->first, size->second);
    }
    if (!in || n >= (std::size_t(64) << 20))
      throw Error(path + (kind == Kind::Jpeg
                              ? ": corrupt JPEG: no frame header (SOF) where its markers lead"
                              : ": corrupt OpenEXR file: no dataWindow in its header"));
  }
}

// OpenCV's Radiance reader accepts a file whose RLE scanlines stop early and returns the image
// with the missing rows left black. A complete file holds at least one RLE (>= 4-byte header per
// scanline) or flat (4 bytes per pixel) record per row, so we check the header's size line against
// the bytes present.
// Checked before OpenCV decodes the file, whose reader reports a short file on stderr itself.
void checkRadianceComplete(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::string line;
  if (!std::getline(f, line) || line.rfind("#?", 0) != 0) return;  // not Radiance: imread decides
  std::size_t headerBytes = line.size() + 1;
  int width = 0, height = 0;
  bool sawSize = false;
  while (std::getline(f, line)) {
    headerBytes += line.size() + 1;
    if (line.rfind("-Y ", 0) == 0 || line.rfind("+Y ", 0) == 0) {
      char x[3] = {};
      sawSize = std::sscanf(line.c_str() + 3, "%d %2s %d", &height, x, &width) == 3 && width > 0 &&
                height > 0;
      break;
    }
  }
  if (!sawSize) throw Error(path + ": Radiance header has no valid resolution line");
  checkPixelCount(path, width, height);
  const auto size = fs::file_size(path);
  const auto payload = size > headerBytes ? size - headerBytes : 0;
  // Decode the scanlines ourselves just far enough to count them.
  f.clear();
  f.seekg(std::streamoff(headerBytes));
  std::vector<unsigned char> data(payload);
  f.read(reinterpret_cast<char*>(data.data()), std::streamsize(payload));
  std::size_t pos = 0;
  for (int row = 0; row < height; ++row) {
    if (pos + 4 > data.size())
      throw Error(path + ": truncated Radiance file (row " + std::to_string(row) + " of " +
                  std::to_string(height) + " missing)");
    const bool rle = width >= 8 && width < 32768 && data[pos] == 2 && data[pos + 1] == 2 &&
                     ((data[pos + 2] << 8) | data[pos + 3]) == width;
    if (!rle) {
      pos += std::size_t(width) * 4;  // flat (or old-style RLE, which we size as flat)
      if (pos > data.size())
        throw Error(path + ": truncated Radiance file (row " + std::to_string(row) + " of " +
                    std::to_string(height) + " incomplete)");
      continue;
    }
    pos += 4;
    for (int ch = 0; ch < 4; ++ch) {
      int x = 0;
      while (x < width) {
        if (pos >= data.size())
          throw Error(path + ": truncated Radiance file (row " + std::to_string(row) + " of " +
                      std::to_string(height) + " incomplete)");
        int n = data[pos++];
        if (n > 128) {  // run
          n -= 128;
          pos += 1;
        } else {
          pos += std::size_t(n);
        }
        if (n == 0 || pos > data.size())
          throw Error(path + ": corrupt or truncated Radiance file at row " + std::to_string(row));
        x += n;
      }
    }
  }
}

bool isPng(const std::string& path) {
  char sig[8] = {};
  std::ifstream(path, std::ios::binary).read(sig, 8);
  return std::memcmp(sig, "\x89PNG\r\n\x1a\n", 8) == 0;
}

// PNG through libpng's simplified API, which keeps its errors and warnings in the png_image
// rather than printing them (OpenCV's PNG reader lets libpng print to stderr). 8-bit files stay
// 8-bit BGR; 16-bit files come out linear (libpng applies the file's gamma, sRGB by default).
void readPng(const std::string& path, Frame& frame) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  struct Free {
    png_image* i;
    ~Free() { png_image_free(i); }
  } release{&img};
  auto fail = [&] {
    throw Error(path + ": not a readable PNG image (" + std::string(img.message) + ")");
  };
  if (!png_image_begin_read_from_file(&img, path.c_str())) fail();
  checkPixelCount(path, img.width, img.height);
  const bool wide = img.format & PNG_FORMAT_FLAG_LINEAR;
  img.format = wide ? PNG_FORMAT_LINEAR_RGB : PNG_FORMAT_BGR;
  frame.width = int(img.width);
  frame.height = int(img.height);
  const std::size_t n = std::size_t(img.width) * img.height * 3;
  if (!wide) {
    frame.format = PanoramaFormat::BgrU8;
    frame.rgb.clear();
    frame.bgr8.resize(n);
    if (!png_image_finish_read(&img, nullptr, frame.bgr8.data(), 0, nullptr)) fail();
    return;
  }
  std::vector<std::uint16_t> linear(n);
  if (!png_image_finish_read(&img, nullptr, linear.data(), 0, nullptr)) fail();
  frame.format = PanoramaFormat::RgbF32;
  frame.bgr8.clear();
  frame.rgb.resize(n);
  for (std::size_t i = 0; i < n; ++i) frame.rgb[i] = float(linear[i]) / 65535.0f;
}

}  // namespace

std::int64_t maxImagePixels() { return gMaxPixels; }
void setMaxImagePixels(std::int64_t pixels) { gMaxPixels = pixels; }

void readImageFrame(const std::string& path, Frame& frame) {
  std::error_code ec;
  requireRegularFile(path);
  const std::string ext = lower(fs::path(path).extension().string());
  if (isPng(path)) return readPng(path, frame);
  if (ext == ".hdr" || ext == ".pic") checkRadianceComplete(path);
  checkHeaderSize(path);
  cv::Mat m;
  try {
    m = cv::imread(path, cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot decode image (" + e.err + ")");
  }
  if (m.empty()) throw Error(path + ": not a readable image (unknown format or corrupt data)");

  cv::Mat bgr;
  switch (m.channels()) {
    case 1:
      cv::cvtColor(m, bgr, cv::COLOR_GRAY2BGR);
      break;
    case 3:
      bgr = m;
      break;
    case 4:
      cv::cvtColor(m, bgr, cv::COLOR_BGRA2BGR);
      break;
    default:
      throw Error(path + ": unsupported channel count " + std::to_string(m.channels()));
  }
  frame.width = bgr.cols;
  frame.height = bgr.rows;
  const std::size_t n = std::size_t(bgr.cols) * bgr.rows * 3;
  if (bgr.depth() == CV_8U) {
    frame.format = PanoramaFormat::BgrU8;
    frame.rgb.clear();
    frame.bgr8.resize(n);
    for (int y = 0; y < bgr.rows; ++y)
      std::copy_n(bgr.ptr<std::uint8_t>(y), std::size_t(bgr.cols) * 3,
                  frame.bgr8.data() + y * std::size_t(bgr.cols) * 3);
    return;
  }
  cv::Mat rgb, f;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  rgb.convertTo(f, CV_32F, bgr.depth() == CV_16U ? 1.0 / 65535.0 : 1.0);
  frame.format = PanoramaFormat::RgbF32;
  frame.bgr8.clear();
  frame.rgb.resize(n);
  for (int y = 0; y < f.rows; ++y)
    std::copy_n(f.ptr<float>(y), std::size_t(f.cols) * 3,
                frame.rgb.data() + y * std::size_t(f.cols) * 3);
  if (bgr.depth() == CV_16U)
    for (float& v : frame.rgb) v = srgbToLinear(v);
  std::size_t bad = 0, firstBad = 0;
  for (std::size_t i = 0; i < frame.rgb.size(); ++i) {
    if (!std::isfinite(frame.rgb[i])) {
      if (bad++ == 0) firstBad = i / 3;
    }
  }
  if (bad)
    throw Error(path + ": " + std::to_string(bad) + " pixel values are NaN or Inf (first at x=" +
                std::to_string(firstBad % frame.width) +
                ", y=" + std::to_string(firstBad / frame.width) + ")");
}

Image loadImage(const std::string& path) {
  Frame f;
  readImageFrame(path, f);
  Image img(f.width, f.height);
  if (f.format == PanoramaFormat::RgbF32) {
    img.rgb = std::move(f.rgb);
    return img;
  }
  std::array<float, 256> lut;
  for (int i = 0; i < 256; ++i) lut[i] = srgbToLinear(i / 255.0f);
  for (std::size_t i = 0; i < f.bgr8.size(); i += 3) {
    img.rgb[i] = lut[f.bgr8[i + 2]];
    img.rgb[i + 1] = lut[f.bgr8[i + 1]];
    img.rgb[i + 2] = lut[f.bgr8[i]];
  }
  return img;
}

namespace {

void writeAtomically(const std::string& path, const cv::Mat& m,
                     const std::vector<int>& params = {}) {
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext.empty()) throw Error(path + ": output needs an extension (.png, .hdr, .exr, .jpg)");
  if (ext == ".hdr" || ext == ".exr") {
    // OpenCV encodes these two only into a file (imencode would leave its own temporary in /tmp
    // when a write fails): written straight to our temporary beside the target, and checked.
    AtomicOutput out(path);
    bool ok = false;
    try {
      ok = cv::imwrite(out.temporary(), m, params);
    } catch (const cv::Exception& e) {
      throw Error(path + ": cannot encode an image as " + ext + " (" + e.err + ")");
    }
    std::error_code ec;
    const auto size = fs::file_size(out.temporary(), ec);
    // The encoders do not all report a short write: a file cut at the size limit is one.
    const auto limit = fileSizeLimit();
    if (!ok || ec || size == 0 || (limit && size >= *limit))
      throw Error(path + ": cannot write (" +
                  describeWriteError(limit && size >= *limit ? EFBIG : 0) + ")");
    out.commit();
    return;
  }
  // Encoded in memory first, so that an encoder's refusal and a failed write (a full disk) are
  // told apart, and the write goes through the one checked, atomic writer.
  std::vector<std::uint8_t> bytes;
  try {
    if (!cv::imencode(ext, m, bytes, params))
      throw Error(path + ": cannot encode an image as " + ext);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot encode an image as " + ext + " (" + e.err + ")");
  } catch (const std::bad_alloc&) {
    throw Error(path + ": out of memory while encoding the image");
  }
  writeFileAtomically(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace

void saveImage(const std::string& path, const Image& img, bool halfFloat) {
  const std::string ext = lower(fs::path(path).extension().string());
  cv::Mat rgb(img.height, img.width, CV_32FC3, const_cast<float*>(img.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  if (ext == ".hdr" || ext == ".exr") {
    if (ext == ".exr" && halfFloat)
      writeAtomically(path, bgr, {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_HALF});
    else
      writeAtomically(path, bgr);
    return;
  }
  cv::Mat out(bgr.rows, bgr.cols, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const float* s = bgr.ptr<float>(y);
    auto* d = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols * 3; ++x)
      d[x] = std::uint8_t(std::lround(255.0f * linearToSrgb(s[x])));
  }
  writeAtomically(path, out);
}

void saveRgb8(const std::string& path, int width, int height, const std::uint8_t* rgb) {
  cv::Mat m(height, width, CV_8UC3, const_cast<std::uint8_t*>(rgb)), bgr;
  cv::cvtColor(m, bgr, cv::COLOR_RGB2BGR);
  writeAtomically(path, bgr);
}

std::vector<std::uint8_t> encodePng8(int width, int height, int channels,
                                     const std::uint8_t* rgba) {
  cv::Mat m(height, width, channels == 4 ? CV_8UC4 : CV_8UC3, const_cast<std::uint8_t*>(rgba)), bgr;
  cv::cvtColor(m, bgr, channels == 4 ? cv::COLOR_RGBA2BGRA : cv::COLOR_RGB2BGR);
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".png", bgr, bytes)) throw Error("cannot encode an image as PNG");
  return bytes;
}

void saveImage8(const std::string& path, int width, int height, int channels,
                const std::uint8_t* data) {
  cv::Mat m(height, width, channels == 4 ? CV_8UC4 : CV_8UC3, const_cast<std::uint8_t*>(data));
  writeAtomically(path, m);
}

std::optional<std::pair<int, int>> jpegFrameSize(const std::uint8_t* p, std::size_t n) {
  std::size_t i = 2;  // after SOI
  while (i + 4 <= n) {
    if (p[i] != 0xFF) return std::nullopt;
    const std::uint8_t m = p[i + 1];
    if (m == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {  // TEM, RSTn: no length
      i += 2;
      continue;
    }
    if (m == 0xDA || m == 0xD9) return std::nullopt;  // SOS or EOI before any SOF
    const std::size_t len = std::size_t(p[i + 2]) << 8 | p[i + 3];
    if (len < 2) return std::nullopt;
    const bool sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
    if (sof) {
      if (len < 7 || i + 9 > n) return std::nullopt;
      return std::pair<int, int>{int(p[i + 7]) << 8 | p[i + 8], int(p[i + 5]) << 8 | p[i + 6]};
    }
    i += 2 + len;
  }
  return std::nullopt;
}

cv::Mat decodeCameraJpeg(const std::uint8_t* data, std::size_t bytes, int reduce) {
  if (bytes < 2 || data[0] != 0xFF || data[1] != 0xD8 ||
      bytes > std::size_t(std::numeric_limits<int>::max()))
    return {};
  const int flags = reduce >= 8   ? cv::IMREAD_REDUCED_COLOR_8
                    : reduce >= 4 ? cv::IMREAD_REDUCED_COLOR_4
                    : reduce >= 2 ? cv::IMREAD_REDUCED_COLOR_2
                                  : cv::IMREAD_COLOR;
  try {  // cv::Mat wraps the bytes, never writes them
    cv::Mat bgr =
        cv::imdecode(cv::Mat(1, int(bytes), CV_8UC1, const_cast<std::uint8_t*>(data)), flags);
    return bgr.type() == CV_8UC3 ? bgr : cv::Mat();
  } catch (const cv::Exception&) {
    return {};
  }
}

void storeBgrFrame(const cv::Mat& bgr, Frame& f) {
  f.format = PanoramaFormat::BgrU8;
  f.rgb.clear();
  f.width = bgr.cols, f.height = bgr.rows;
  f.bgr8.resize(std::size_t(bgr.cols) * std::size_t(bgr.rows) * 3);
  for (int y = 0; y < bgr.rows; ++y)
    std::memcpy(f.bgr8.data() + std::size_t(y) * std::size_t(bgr.cols) * 3, bgr.ptr(y),
                std::size_t(bgr.cols) * 3);
}

}  // namespace lp
