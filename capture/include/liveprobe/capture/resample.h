#pragma once
// Image operations on panoramas: resampling any layout to an equirect, and reducing an equirect
// by an integer factor. The geometry comes from the SH core (liveprobe/sh/layout.h).
#include "liveprobe/capture/image.h"
#include "liveprobe/sh/layout.h"

namespace lp {

/// Resamples a frame of any layout to a W x H equirect (bilinear, at the equirect's pixel
/// centres); directions the layout does not see are black.
Image resampleToEquirect(const Image& frame, const LayoutSpec& spec, int width, int height);

/// Whether GL draws a panorama of this layout behind the model as it is (equirect, angular).
/// Any other (cube, mirror ball, fisheye) is drawn through displayEquirect, made on capture's
/// thread for a stream.
bool displayDrawsAsIs(const LayoutSpec& layout);
/// The layout the display draws a panorama of `layout` in: its own, or equirect.
Layout displayLayout(const LayoutSpec& layout);
/// The display's 1024 x 512 equirect of a panorama that GL does not draw as it is.
Image displayEquirect(const Image& frame, const LayoutSpec& layout);

/// An equirect reduced by an integer factor f: each output pixel is the solid-angle-weighted
/// mean of an f x f block (so the block's radiant power is kept exactly). Irradiance is
/// low-frequency: projecting the reduced frame changes the coefficients by a small, measured
/// amount (README; the test bounds it at 0.1% of L00 for f = 4 on 1K HDRs), for 1/f^2 the work.
/// W and H must be multiples of f.
Image reduceEquirect(const float* rgb, int width, int height, int factor);
/// The same into `out`, whose storage is reused (a stream reduces every frame).
void reduceEquirect(const float* rgb, int width, int height, int factor, Image& out);

}  // namespace lp
