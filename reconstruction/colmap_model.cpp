#include "reconstruction/colmap_model.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <vector>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// One non-comment line of a COLMAP text file, split on white space.
struct Line {
  int number = 0;
  std::vector<std::string> fields;
};

Result<std::vector<Line>> ReadLines(const fs::path& path, bool keep_empty) {
  std::ifstream in(path);
  if (!in)
    return NotFound(path.string() +
                    ": missing (a COLMAP text model has cameras.txt and images.txt)");
  std::vector<Line> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text[0] == '#') continue;
    Line line{number, {}};
    std::istringstream words(text);
    for (std::string w; words >> w;) line.fields.push_back(w);
    if (line.fields.empty() && !keep_empty) continue;
    lines.push_back(std::move(line));
  }
  return lines;
}

Status LineError(const fs::path& path, const Line& line, const std::string& what) {
  return CorruptData(path.string() + ":" + std::to_string(line.number) + ": " + what);
}

Result<double> Number(const fs::path& path, const Line& line, size_t index, const char* name) {
  if (index >= line.fields.size()) return LineError(path, line, std::string("missing ") + name);
  const std::string& text = line.fields[index];
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) {
    return LineError(path, line, std::string(name) + " '" + text + "' is not a finite number");
  }
  return value;
}

Result<int> Integer(const fs::path& path, const Line& line, size_t index, const char* name) {
  HR_ASSIGN_OR_RETURN(const double value, Number(path, line, index, name));
  if (value != std::floor(value) || value < 0 || value > 1e9) {
    return LineError(
        path, line, std::string(name) + " '" + line.fields[index] + "' is not a whole number >= 0");
  }
  return static_cast<int>(value);
}

// The parameter count and the intrinsics of each supported model.
Result<CameraIntrinsics> CameraFromLine(const fs::path& path, const Line& line) {
  if (line.fields.size() < 4)
    return LineError(path, line, "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS...");
  const std::string& model = line.fields[1];
  static const std::map<std::string, size_t> kParams = {
      {"PINHOLE", 4}, {"SIMPLE_RADIAL", 4}, {"RADIAL", 5}, {"OPENCV", 8}, {"FULL_OPENCV", 12}};
  const auto known = kParams.find(model);
  if (known == kParams.end()) {
    return LineError(path, line,
                     "camera model '" + model +
                         "' is not supported (use PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV "
                         "or FULL_OPENCV; undistort the images with COLMAP's image_undistorter for "
                         "other models)");
  }
  if (line.fields.size() != 4 + known->second) {
    return LineError(path, line,
                     model + " takes " + std::to_string(known->second) +
                         " parameters, the line has " + std::to_string(line.fields.size() - 4));
  }
  std::vector<double> p;
  for (size_t k = 4; k < line.fields.size(); ++k) {
    HR_ASSIGN_OR_RETURN(const double v, Number(path, line, k, "a camera parameter"));
    p.push_back(v);
  }
  CameraIntrinsics c;
  HR_ASSIGN_OR_RETURN(c.width_px, Integer(path, line, 2, "WIDTH"));
  HR_ASSIGN_OR_RETURN(c.height_px, Integer(path, line, 3, "HEIGHT"));
  if (model == "SIMPLE_RADIAL" || model == "RADIAL") {
    c.fx_px = c.fy_px = p[0];
    c.cx_px = p[1];
    c.cy_px = p[2];
    c.k1 = p[3];
    if (model == "RADIAL") c.k2 = p[4];
  } else {
    c.fx_px = p[0];
    c.fy_px = p[1];
    c.cx_px = p[2];
    c.cy_px = p[3];
    if (p.size() >= 8) {
      c.k1 = p[4];
      c.k2 = p[5];
      c.p1 = p[6];
      c.p2 = p[7];
    }
    if (p.size() == 12) {
      c.k3 = p[8];
      if (p[9] != 0 || p[10] != 0 || p[11] != 0) {
        return LineError(
            path, line,
            "FULL_OPENCV with k4, k5 or k6 not 0 is not supported (rational lens model)");
      }
    }
  }
  // COLMAP's pixel centres are at +0.5 (see the header).
  c.cx_px -= 0.5;
  c.cy_px -= 0.5;
  const Status valid = c.Validate();
  if (!valid.ok()) return LineError(path, line, valid.message());
  return c;
}

Result<Rigid3d> PoseFromLine(const fs::path& path, const Line& line) {
  double v[7];
  const char* names[7] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
  for (int k = 0; k < 7; ++k) {
    HR_ASSIGN_OR_RETURN(v[k], Number(path, line, static_cast<size_t>(1 + k), names[k]));
  }
  const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    return LineError(path, line,
                     "the quaternion QW QX QY QZ has norm " + std::to_string(q.norm()) + ", not 1");
  }
  return Rigid3d(q, Eigen::Vector3d(v[4], v[5], v[6]));
}

std::string MaskPathFor(const std::string& masks_dir, const std::string& name) {
  if (masks_dir.empty()) return {};
  const fs::path colmap_style = fs::path(masks_dir) / (name + ".png");
  if (fs::exists(colmap_style)) return colmap_style.string();
  const fs::path stem_style =
      fs::path(masks_dir) / fs::path(name).filename().replace_extension(".png");
  if (fs::exists(stem_style)) return stem_style.string();
  return {};
}

}  // namespace

Result<ReconstructionInput> ReadColmapModel(const std::string& model_dir,
                                            const ColmapReadOptions& options) {
  const fs::path cameras_txt = fs::path(model_dir) / "cameras.txt";
  const fs::path images_txt = fs::path(model_dir) / "images.txt";
  HR_ASSIGN_OR_RETURN(const std::vector<Line> camera_lines, ReadLines(cameras_txt, false));
  std::map<int, CameraIntrinsics> cameras;
  for (const Line& line : camera_lines) {
    HR_ASSIGN_OR_RETURN(const int id, Integer(cameras_txt, line, 0, "CAMERA_ID"));
    HR_ASSIGN_OR_RETURN(cameras[id], CameraFromLine(cameras_txt, line));
  }
  // images.txt: an image line, then its line of 2D points (maybe empty).
  HR_ASSIGN_OR_RETURN(const std::vector<Line> image_lines, ReadLines(images_txt, true));
  ReconstructionInput input;
  input.object_frame = "colmap world";
  for (size_t i = 0; i < image_lines.size(); ++i) {
    const Line& line = image_lines[i];
    if (line.fields.empty()) continue;  // a blank line where an image line may stand
    if (line.fields.size() != 10) {
      return LineError(images_txt, line,
                       "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 fields), got " +
                           std::to_string(line.fields.size()));
    }
    ReconstructionView view;
    HR_ASSIGN_OR_RETURN(view.id, Integer(images_txt, line, 0, "IMAGE_ID"));
    HR_ASSIGN_OR_RETURN(view.cam_from_object, PoseFromLine(images_txt, line));
    HR_ASSIGN_OR_RETURN(const int camera_id, Integer(images_txt, line, 8, "CAMERA_ID"));
    const auto camera = cameras.find(camera_id);
    if (camera == cameras.end()) {
      return LineError(images_txt, line,
                       "camera " + std::to_string(camera_id) + " is not in cameras.txt");
    }
    view.camera = camera->second;
    view.name = fs::path(line.fields[9]).stem().string();
    view.image_path = (fs::path(options.images_dir) / line.fields[9]).string();
    view.mask_path = MaskPathFor(options.masks_dir, line.fields[9]);
    ++i;  // the points line that follows
    if (!fs::exists(view.image_path)) {
      input.left_out.push_back(view.name + ": " + view.image_path + " is missing");
      continue;
    }
    input.views.push_back(std::move(view));
  }
  if (input.views.empty()) {
    return NotFound(images_txt.string() + ": no image of the model is present in " +
                    options.images_dir);
  }
  return input;
}

}  // namespace hairrig
