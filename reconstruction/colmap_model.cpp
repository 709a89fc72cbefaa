#include "reconstruction/colmap_model.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <string_view>
#include <vector>

#include "core/file_util.h"
#include "core/image_file.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// One non-comment line of a COLMAP text file, split on white space.
struct Line {
  int number = 0;
  std::vector<std::string> fields;
};

Line SplitLine(int number, std::string_view text) {
  Line line{number, {}};
  size_t at = 0;
  for (;;) {
    while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
    if (at == text.size()) return line;
    const size_t start = at;
    while (at < text.size() && !std::isspace(static_cast<unsigned char>(text[at]))) ++at;
    line.fields.emplace_back(text.substr(start, at - start));
  }
}

// Calls `visit` with each line of `path` that is not a comment ('#' first),
// numbered from 1, up to the first error. The file is read with
// ReadFileText's checks: a regular file (never a FIFO or a device) of at most
// kMaxFileBytes.
Status ForEachLine(const fs::path& path,
                   const std::function<Status(int number, std::string_view text)>& visit) {
  Result<std::string> read = ReadFileText(path.string(), kMaxFileBytes);
  if (read.status().code() == StatusCode::kNotFound)
    return NotFound(path.string() +
                    ": missing (a COLMAP text model has cameras.txt and images.txt)");
  HR_RETURN_IF_ERROR(read.status());
  const std::string_view text = *read;
  int number = 1;
  for (size_t at = 0; at < text.size(); ++number) {
    const size_t end = std::min(text.find('\n', at), text.size());
    const std::string_view line = text.substr(at, end - at);
    if (line.empty() || line[0] != '#') HR_RETURN_IF_ERROR(visit(number, line));
    at = end + 1;
  }
  return Status::Ok();
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
  const Status valid = c.Check();
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

// The line where `key` was first seen, 0 the first time (then it is noted at `number`).
template <typename Key>
int EarlierLine(std::map<Key, int>* seen, const Key& key, int number) {
  const auto [first, inserted] = seen->emplace(key, number);
  return inserted ? 0 : first->second;
}

Result<std::map<int, CameraIntrinsics>> ReadCameras(const fs::path& cameras_txt) {
  std::map<int, CameraIntrinsics> cameras;
  std::map<int, int> lines;
  HR_RETURN_IF_ERROR(ForEachLine(cameras_txt, [&](int number, std::string_view text) -> Status {
    const Line line = SplitLine(number, text);
    if (line.fields.empty()) return Status::Ok();
    HR_ASSIGN_OR_RETURN(const int id, Integer(cameras_txt, line, 0, "CAMERA_ID"));
    if (const int earlier = EarlierLine(&lines, id, number)) {
      return LineError(cameras_txt, line,
                       "CAMERA_ID " + std::to_string(id) + " repeats line " +
                           std::to_string(earlier) + " (each camera is listed once)");
    }
    HR_ASSIGN_OR_RETURN(cameras[id], CameraFromLine(cameras_txt, line));
    return Status::Ok();
  }));
  return cameras;
}

// What the image lines read so far hold, so that a repeat is refused.
struct ImagesSeen {
  std::map<int, int> ids;                 // IMAGE_ID -> line
  std::map<std::string, int> names;       // NAME, lexically normal -> line
  std::map<std::string, int> view_names;  // ReconstructionView::name (NAME's stem) -> line
};

// NAME of an image line as a relative path; CorruptData naming the line and
// NAME when it is absolute or has a '..' component, either of which leaves
// the images folder, or has a control character.
Result<fs::path> ImageName(const fs::path& images_txt, const Line& line,
                           const std::string& images_dir) {
  const std::string& name = line.fields[9];
  for (const unsigned char c : name) {
    if (c < 0x20 || c == 0x7f)
      return LineError(images_txt, line,
                       "image NAME has a control character (byte " + std::to_string(c) + ")");
  }
  const fs::path path(name);
  const std::string shown = "image NAME '" + name + "'";
  if (path.is_absolute()) {
    return LineError(images_txt, line,
                     shown + " is absolute; names are relative to the images folder " + images_dir);
  }
  for (const fs::path& part : path) {
    if (part == "..") {
      return LineError(
          images_txt, line,
          shown + " has a '..' component; names stay in the images folder " + images_dir);
    }
  }
  return path.lexically_normal();
}

// The line's IMAGE_ID, pose, camera and NAME (as a relative path), each
// checked; IMAGE_ID, NAME and the view name a repeat of none before.
Result<ReconstructionView> ViewFromLine(const fs::path& images_txt, const Line& line,
                                        const std::map<int, CameraIntrinsics>& cameras,
                                        const std::string& images_dir, ImagesSeen* seen,
                                        fs::path* name) {
  if (line.fields.size() != 10) {
    return LineError(images_txt, line,
                     "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 fields), got " +
                         std::to_string(line.fields.size()));
  }
  ReconstructionView view;
  HR_ASSIGN_OR_RETURN(view.id, Integer(images_txt, line, 0, "IMAGE_ID"));
  if (const int earlier = EarlierLine(&seen->ids, view.id, line.number)) {
    return LineError(images_txt, line,
                     "IMAGE_ID " + std::to_string(view.id) + " repeats line " +
                         std::to_string(earlier) + " (each image is listed once)");
  }
  HR_ASSIGN_OR_RETURN(view.cam_from_object, PoseFromLine(images_txt, line));
  HR_ASSIGN_OR_RETURN(const int camera_id, Integer(images_txt, line, 8, "CAMERA_ID"));
  const auto camera = cameras.find(camera_id);
  if (camera == cameras.end()) {
    return LineError(images_txt, line,
                     "camera " + std::to_string(camera_id) + " is not in cameras.txt");
  }
  view.camera = camera->second;
  HR_ASSIGN_OR_RETURN(*name, ImageName(images_txt, line, images_dir));
  const std::string shown = "image NAME '" + line.fields[9] + "'";
  if (const int earlier = EarlierLine(&seen->names, name->string(), line.number)) {
    return LineError(
        images_txt, line,
        shown + " repeats line " + std::to_string(earlier) + " (each image is listed once)");
  }
  view.name = name->stem().string();
  if (const int earlier = EarlierLine(&seen->view_names, view.name, line.number)) {
    return LineError(images_txt, line,
                     shown + " gives the view name '" + view.name + "' of line " +
                         std::to_string(earlier) +
                         " too (views, and the files written for them, are named by the image's "
                         "file name without its extension; rename one)");
  }
  return view;
}

// `name` below `folder` with its symlinks resolved: CorruptData when that
// leads out of `folder`; when the file exists, the errors of CheckImageFile
// (not a regular file, such as a FIFO or a device; more pixels than
// kMaxImagePixels; not an image).
Result<std::string> ImageInside(const std::string& folder, const fs::path& name) {
  HR_ASSIGN_OR_RETURN(std::string path, ResolveInside((fs::path(folder) / name).string(), folder));
  std::error_code ec;
  if (fs::exists(path, ec)) HR_RETURN_IF_ERROR(CheckImageFile(path));
  return path;
}

// <masks_dir>/<NAME>.png (COLMAP's convention) or <masks_dir>/<stem>.png,
// checked as ImageInside does; "" when there is neither.
Result<std::string> MaskPathFor(const std::string& masks_dir, const fs::path& name) {
  if (masks_dir.empty()) return std::string();
  fs::path stem_style = name.filename();
  stem_style.replace_extension(".png");
  for (const fs::path& candidate : {fs::path(name.string() + ".png"), stem_style}) {
    HR_ASSIGN_OR_RETURN(std::string path, ImageInside(masks_dir, candidate));
    std::error_code ec;
    if (fs::exists(path, ec)) return path;
  }
  return std::string();
}

// Adds the view of one image line to `input`, or names it in
// input->left_out when its file is missing.
Status AddImage(const fs::path& images_txt, const Line& line,
                const std::map<int, CameraIntrinsics>& cameras, const ColmapReadOptions& options,
                ImagesSeen* seen, ReconstructionInput* input) {
  fs::path name;
  HR_ASSIGN_OR_RETURN(ReconstructionView view,
                      ViewFromLine(images_txt, line, cameras, options.images_dir, seen, &name));
  const std::string context = images_txt.string() + ":" + std::to_string(line.number) +
                              ": image NAME '" + line.fields[9] + "'";
  Result<std::string> image = ImageInside(options.images_dir, name);
  if (!image.ok()) return image.status().WithContext(context);
  std::error_code ec;
  if (!fs::exists(*image, ec)) {
    input->left_out.push_back(view.name + ": " + *image + " is missing");
    return Status::Ok();
  }
  view.image_path = *image;
  Result<std::string> mask = MaskPathFor(options.masks_dir, name);
  if (!mask.ok()) return mask.status().WithContext(context + ", its mask");
  view.mask_path = *mask;
  input->views.push_back(std::move(view));
  return Status::Ok();
}

}  // namespace

Status ColmapReadOptions::Check() const {
  if (images_dir.empty())
    return InvalidArgument("images_dir (the folder the model's image names are in) is required");
  return Status::Ok();
}

Result<ReconstructionInput> ReadColmapModel(const std::string& model_dir,
                                            const ColmapReadOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("COLMAP model " + model_dir));
  const fs::path cameras_txt = fs::path(model_dir) / "cameras.txt";
  const fs::path images_txt = fs::path(model_dir) / "images.txt";
  HR_ASSIGN_OR_RETURN(const auto cameras, ReadCameras(cameras_txt));
  ReconstructionInput input;
  input.object_frame = "colmap world";
  ImagesSeen seen;
  // images.txt: an image line, then its line of 2D points (maybe empty).
  bool points_line_next = false;
  HR_RETURN_IF_ERROR(ForEachLine(images_txt, [&](int number, std::string_view text) -> Status {
    if (points_line_next) {
      points_line_next = false;
      return Status::Ok();
    }
    const Line line = SplitLine(number, text);
    if (line.fields.empty()) return Status::Ok();  // a blank line where an image line may stand
    points_line_next = true;
    return AddImage(images_txt, line, cameras, options, &seen, &input);
  }));
  if (input.views.empty()) {
    return NotFound(images_txt.string() + ": no image of the model is present in " +
                    options.images_dir);
  }
  return input;
}

}  // namespace hairrig
