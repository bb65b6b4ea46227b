// OpenCV's image codecs, loaded on first use (image_file.h says why).
#include <dlfcn.h>

#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "vio/dataset/image_file.h"

namespace vio::tools {
namespace {

using ImreadFunction = cv::Mat (*)(const cv::String&, int);
using ImdecodeFunction = cv::Mat (*)(cv::InputArray, int);
using ImwriteFunction = bool (*)(const cv::String&, cv::InputArray, const std::vector<int>&);
// Each cast compiles only when opencv2/imgcodecs.hpp declares a function of exactly that type
// (unevaluated: nothing is linked), so the Itanium-mangled names below, which encode these
// signatures, are the declared functions'.
static_assert(sizeof(static_cast<ImreadFunction>(&cv::imread)) > 0);
static_assert(sizeof(static_cast<ImdecodeFunction>(&cv::imdecode)) > 0);
static_assert(sizeof(static_cast<ImwriteFunction>(&cv::imwrite)) > 0);
static_assert(std::is_same_v<cv::String, std::string>);
constexpr char kImreadSymbol[] = "_ZN2cv6imreadERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEEi";
constexpr char kImdecodeSymbol[] = "_ZN2cv8imdecodeERKNS_11_InputArrayEi";
constexpr char kImwriteSymbol[] =
    "_ZN2cv7imwriteERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEERKNS_11_InputArrayERKSt6vectorIiSaIiEE";

struct OpenCvCodecs {
  ImreadFunction imread = nullptr;
  ImdecodeFunction imdecode = nullptr;
  ImwriteFunction imwrite = nullptr;
};

template <typename Function>
Function CodecSymbol(void* library, const char* name) {
  void* address = dlsym(library, name);
  if (address == nullptr) {
    throw std::runtime_error(std::string(VIO_OPENCV_IMGCODECS_LIBRARY) + " has no " + name +
                             " (not the OpenCV this was built with)");
  }
  return reinterpret_cast<Function>(address);
}

OpenCvCodecs LoadOpenCvCodecs() {
  // Kept loaded for the rest of the process (never dlclose'd).
  void* library = dlopen(VIO_OPENCV_IMGCODECS_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    throw std::runtime_error(std::string("cannot load OpenCV's image codecs: ") + dlerror());
  }
  return {CodecSymbol<ImreadFunction>(library, kImreadSymbol), CodecSymbol<ImdecodeFunction>(library, kImdecodeSymbol),
          CodecSymbol<ImwriteFunction>(library, kImwriteSymbol)};
}

const OpenCvCodecs& LoadedOpenCvCodecs() {
  static const OpenCvCodecs codecs = LoadOpenCvCodecs();  // a failed load throws, and the next call tries again
  return codecs;
}

}  // namespace

cv::Mat ImageRead(const std::string& path, int flags) { return LoadedOpenCvCodecs().imread(path, flags); }

cv::Mat ImageDecode(const cv::Mat& bytes, int flags) { return LoadedOpenCvCodecs().imdecode(bytes, flags); }

bool ImageWrite(const std::string& path, const cv::Mat& image, const std::vector<int>& params) {
  return LoadedOpenCvCodecs().imwrite(path, image, params);
}

}  // namespace vio::tools
