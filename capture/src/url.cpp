// URLs: which name a network stream, and how one is shown (liveprobe/capture/network.h). Built
// with or without FFmpeg: a build without it still says what a URL is.
#include <algorithm>
#include <cctype>
#include <iterator>
#include <string>

#include "liveprobe/capture/network.h"

namespace lp {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const char* const kSchemes[] = {"rtsp",  "rtsps", "rtmp", "rtmps", "http",
                                "https", "srt",   "udp",  "rtp",   "tcp"};

}  // namespace

bool isNetworkUrl(const std::string& spec) {
  const std::size_t at = spec.find("://");
  if (at == std::string::npos) return false;
  const std::string scheme = lower(spec.substr(0, at));
  return std::find(std::begin(kSchemes), std::end(kSchemes), scheme) != std::end(kSchemes);
}

std::string redactUrl(const std::string& url) {
  const std::size_t at = url.find("://");
  if (at == std::string::npos) return url;
  std::string out = url;
  // The authority: [user[:password]@]host[:port], up to the path, the query or the fragment.
  const std::size_t start = at + 3;
  const std::size_t end = std::min(out.find_first_of("/?#", start), out.size());
  const std::size_t atSign = out.rfind('@', end == out.size() ? std::string::npos : end - 1);
  if (atSign != std::string::npos && atSign >= start && atSign < end) {
    const std::size_t colon = out.find(':', start);
    if (colon != std::string::npos && colon < atSign)
      out.replace(colon + 1, atSign - colon - 1, "***");
  }
  // Secret query values.
  static const char* const kSecret[] = {"passphrase", "password", "passwd", "pass", "pwd",
                                        "key",        "token",    "secret", "auth"};
  std::size_t q = out.find('?');
  while (q != std::string::npos) {
    const std::size_t keyStart = q + 1;
    const std::size_t eq = out.find('=', keyStart);
    const std::size_t amp = out.find_first_of("&#", keyStart);
    if (eq == std::string::npos || (amp != std::string::npos && amp < eq)) {
      q = amp != std::string::npos && out[amp] == '&' ? amp : std::string::npos;
      continue;
    }
    const std::string key = lower(out.substr(keyStart, eq - keyStart));
    const std::size_t valueEnd = amp == std::string::npos ? out.size() : amp;
    if (std::find_if(std::begin(kSecret), std::end(kSecret),
                     [&](const char* k) { return key == k; }) != std::end(kSecret))
      out.replace(eq + 1, valueEnd - eq - 1, "***");
    const std::size_t next = out.find_first_of("&#", eq + 1);
    q = next != std::string::npos && out[next] == '&' ? next : std::string::npos;
  }
  return out;
}

}  // namespace lp
