// The report's pictures: scenes drawn by `stepwise render` (this same binary), a still and an animation each.
#pragma once

#include <filesystem>
#include <string>

namespace stepwise {

// renders each pictured scene from scenes_dir into dir/pictures/SCENE, writes dir/pictures.csv, and returns
// the report's section; std::runtime_error naming the scene whose render failed
std::string pictures_section(const std::filesystem::path& dir, const std::filesystem::path& scenes_dir, bool quick);

}  // namespace stepwise
