// The report's pictures: every scene drawn by `stepwise render` (this same binary), a still and an animation each.
#pragma once

#include <stepwise/report/studies.hpp>

#include <filesystem>
#include <string>

namespace stepwise {

// the pictures study, a drawn one: every scene of the context's scenes_dir rendered into its out/pictures/SCENE (the
// renders run as the context's sweep), with pictures.csv; std::runtime_error naming the scene whose render failed
Study pictures_study();

// a scene file's leading comment, its lines joined without their '#': the scene's own description
std::string scene_description(const std::filesystem::path& scene_file);

}  // namespace stepwise
