// The report's pictures: every scene drawn by `stepwise render` (this same binary), a still and an animation each.
#pragma once

#include <stepwise/report/sweep.hpp>

#include <filesystem>
#include <string>

namespace stepwise {

// renders every scene of scenes_dir into dir/pictures/SCENE (the renders run as the context's sweep), writes
// dir/pictures.csv, and returns the report's section; std::runtime_error naming the scene whose render failed
std::string pictures_section(const std::filesystem::path& dir, const std::filesystem::path& scenes_dir, const StudyContext& ctx);

// a scene file's leading comment, its lines joined without their '#': the scene's own description
std::string scene_description(const std::filesystem::path& scene_file);

}  // namespace stepwise
