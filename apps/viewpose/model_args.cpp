#include "model_args.hpp"

#include <spdlog/spdlog.h>

#include "viewpose/io/object_models.hpp"

namespace viewpose::cli {

std::vector<ObjectModel> load_models(const std::vector<std::string>& models, LengthUnit unit) {
  LoadedObjectModels loaded = load_object_models(models, unit);
  for (const std::string& w : loaded.warnings) spdlog::warn("{}", w);
  return std::move(loaded.objects);
}

}  // namespace viewpose::cli
