#pragma once
// A chrome ball found in a camera's frame (--circle auto): OpenCV's gradient Hough transform for
// where it is, its rim's edge along rays out of the centre for a circle to a pixel or so, then
// the rim's own model fitted to a tenth of a pixel (what the orthographic ball's rim asks: a
// fifth of a pixel of radius moves its coefficients by about 0.4% of L00).
#include <array>
#include <optional>

#include "liveprobe/frame/frame.h"

namespace lp {

/// A circle in pixel coordinates (x right, y down, pixel centres at +0.5, as layoutPixel), and
/// how well the rim's model fitted it.
struct BallCircle {
  double x = 0, y = 0, radius = 0;
  double rimResidual = 0;  ///< RMS distance of the sectors' rim edges from the circle, pixels
  int rimSectors = 0;      ///< sectors (of 32) whose edge the circle kept
  double rimBlur = 0;      ///< the camera's blur the rim's model fitted best (Gaussian sigma, px)
};

/// The ball in `frame` (8-bit or float): the circle of a radius from a tenth to a half of the
/// frame's shorter side whose rim holds (the rim's edges within 0.5 px RMS of it), or none.
std::optional<BallCircle> findBall(const Frame& frame);

/// A rectangle of a frame, in pixels.
struct FrameWindow {
  int x = 0, y = 0, width = 0, height = 0;
};
/// findBall in `window` of the frame (the circle in the whole frame's coordinates): where only
/// part of the frame holds the scene (a fisheye's image circle, black around it, whose edge is a
/// stronger circle than the ball's; a ball on the lens's axis shares its centre).
std::optional<BallCircle> findBallWithin(const Frame& frame, const FrameWindow& window);

/// The ball followed through a stream (--circle auto on replay, live and view). The first frame
/// that holds it is searched whole (findBall); after that each frame's rim is read about the
/// circle in use, cheaply (its strongest radial edge, within a band of the radius, in a window
/// around the ball), and compared with the reading the circle was fitted with: the circle is
/// fitted again (the rim's model, as findBall's) only when the rim has moved by more than
/// kMovedPixels, so a still ball keeps one circle (no jitter in the coefficients) and a ball that
/// moves costs a fit per frame it moves. A frame whose rim does not read as a circle near the last
/// one (a hand in front, the ball knocked away) is lost: the last circle is kept and said lost,
/// the ball is sought near it each frame and in the whole frame every kSearchEvery frames.
class BallFollower {
 public:
  static constexpr double kMovedPixels = 0.2;  ///< about 0.4% of L00 in the circle's radius
  static constexpr int kSearchEvery = 15;
  enum class Event { None, Found, Moved, Lost, FoundAgain };
  /// `searchWithin`: where the whole-frame searches look (findBallWithin); none: the frame.
  explicit BallFollower(std::optional<FrameWindow> searchWithin = std::nullopt)
      : searchWithin_(searchWithin) {}
  struct Step {
    std::optional<BallCircle> circle;  ///< to project with; none before the ball is first found
    bool lost = false;                 ///< not seen in this frame: `circle` is the last one
    Event event = Event::None;         ///< what this frame changed
  };
  Step follow(const Frame& frame);

 private:
  std::optional<FrameWindow> searchWithin_;
  std::optional<BallCircle> circle_;
  std::array<double, 3> reading_{};  ///< the rim's edge reading the circle was fitted with
  bool lost_ = false;
  int lostFrames_ = 0;
};

}  // namespace lp
