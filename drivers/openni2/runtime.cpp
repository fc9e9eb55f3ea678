#include "runtime.hpp"

#include <OpenNI.h>

#include <algorithm>
#include <mutex>
#include <vector>

#include "rgbdmap/base/error.hpp"

namespace rgbdmap::openni2 {
namespace {

std::mutex& usersMutex() {
  static std::mutex instance;
  return instance;
}

int& users() {
  static int count = 0;
  return count;
}

}  // namespace

std::shared_ptr<Runtime> Runtime::acquire() {
  std::lock_guard<std::mutex> lock(usersMutex());
  if (users() == 0 && openni::OpenNI::initialize() != openni::STATUS_OK)
    throw InputError(std::string("OpenNI2 cannot start: ") + openni::OpenNI::getExtendedError());
  ++users();
  return std::shared_ptr<Runtime>(new Runtime, [](Runtime* runtime) {
    delete runtime;
    std::lock_guard<std::mutex> lock(usersMutex());
    if (--users() == 0) openni::OpenNI::shutdown();
  });
}

std::string lastError() {
  std::string text = openni::OpenNI::getExtendedError();
  std::replace(text.begin(), text.end(), '\t', ' ');
  std::replace(text.begin(), text.end(), '\n', ' ');
  const auto first = text.find_first_not_of(' ');
  const auto last = text.find_last_not_of(' ');
  return first == std::string::npos ? "no details" : text.substr(first, last - first + 1);
}

void keepUntilExit(std::shared_ptr<void> object) {
  static std::mutex mutex;
  static auto* kept = new std::vector<std::shared_ptr<void>>();
  std::lock_guard<std::mutex> lock(mutex);
  kept->push_back(std::move(object));
}

}  // namespace rgbdmap::openni2
