#pragma once
// Still images in and out, through OpenCV imgcodecs: Radiance .hdr, OpenEXR, and 8/16-bit PNG or
// JPEG (decoded from sRGB to linear radiance). Pixels are linear RGB floats, packed, row-major.
#include <cstdint>
#include <string>
#include <vector>

#include "liveprobe/frame/srgb.h"
#include "liveprobe/sh/image.h"

namespace lp {

/// The most pixels an image file may declare: checked from its header before anything is
/// decoded (PNG, Radiance, JPEG and OpenEXR here; other formats by OpenCV's own limit, 2^30
/// unless OPENCV_IO_MAX_IMAGE_PIXELS is in the environment when the program starts). Default
/// 268,435,456 (2^28).
inline constexpr std::int64_t kDefaultMaxImagePixels = std::int64_t(1) << 28;
std::int64_t maxImagePixels();
void setMaxImagePixels(std::int64_t pixels);

struct Frame;

/// Reads an image file into a frame without changing its encoding: 8-bit files stay 8-bit BGR
/// (decoded later by the photometry stage), HDR files become linear float; 16-bit files are
/// decoded from sRGB to float. Same checks and errors as loadImage.
void readImageFrame(const std::string& path, Frame& frame);

/// Loads `path` as linear RGB. Throws lp::Error naming the file on: a missing or unreadable file,
/// a file that is not an image, a truncated Radiance file, and NaN or Inf pixels.
Image loadImage(const std::string& path);

/// Writes `img` to `path` (.hdr, .exr: linear float; .png, .jpg: 8-bit sRGB of the clamped
/// linear values). Written to a temporary file beside `path`, then renamed, so a failure never
/// leaves a half-written file. Throws lp::Error. `halfFloat`: an .exr holds 16-bit floats
/// (11 significant bits, a quarter of the size after compression; a recording's frames).
void saveImage(const std::string& path, const Image& img, bool halfFloat = false);

/// Writes 8-bit sRGB RGB pixels (rows top to bottom) atomically, as saveImage does.
void saveRgb8(const std::string& path, int width, int height, const std::uint8_t* rgb);

/// 8-bit RGB (channels 3) or RGBA (4) pixels, rows top to bottom, as the bytes of a PNG file.
/// Throws lp::Error.
std::vector<std::uint8_t> encodePng8(int width, int height, int channels, const std::uint8_t* rgba);

/// Writes already-encoded 8-bit BGR(A) pixels (OpenCV order) atomically, as saveImage does.
void saveImage8(const std::string& path, int width, int height, int channels,
                const std::uint8_t* data);

}  // namespace lp
