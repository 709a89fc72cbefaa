// Reading YAML configuration with errors that name the file, line and field.
//
//   HR_ASSIGN_OR_RETURN(ConfigNode root, ConfigNode::LoadFile("etc/sim-rig.yaml"));
//   double fx = root.Child("camera").Number("fx_px", {.min = 1});
//   if (!root.ok()) return root.status();
//     -> "etc/sim-rig.yaml:12:7: field 'camera.fx_px': expected a number >= 1, got 'abc'"
//
// Accessors never throw and never abort: a missing or malformed field records
// the first error in state shared by every node of the document and returns a
// neutral value (0, "", empty), so a loader reads all its fields and then checks
// `status()` once. Optional fields take a fallback.
//
// A document is read whole or refused with its file:line: one YAML document
// (a second one after `---` is an error), every map key text and given once
// at any level (no first-wins), at most kMaxConfigBytes, kMaxConfigValues
// values and kMaxConfigDepth levels; LoadFile reads regular files only (a
// FIFO or a device is refused, never waited on), every text (key or value)
// valid UTF-8. Messages quote a short value with QuotedExcerpt and give a long
// one (over 40 bytes, or with control characters) by its length only.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace hairrig {

// Limits on one config document, checked before it is built into nodes
// (hand-written configs are a few kilobytes and a few hundred values).
inline constexpr size_t kMaxConfigBytes = size_t{1} << 20;
inline constexpr int kMaxConfigValues = 100000;  // scalars, lists and maps
inline constexpr int kMaxConfigDepth = 64;       // nested lists and maps

// `text` quoted for an error message and cut to at most 60 bytes (control
// characters shown as '?'): 'root:x:0:0:root:/root:/bin/bash daemo...' (1843 bytes).
std::string QuotedExcerpt(std::string_view text);

struct NumberRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

// Ranges the rig, scene and box files share, far beyond any real rig (a
// value outside is a mistake, and one such as 1e300 overflows the geometry):
inline constexpr NumberRange kPositionRangeMm{-1e5, 1e5};  // 100 m from the origin
inline constexpr NumberRange kDirectionRange{-1e6, 1e6};   // a direction's components, any scale
inline constexpr NumberRange kRotationRangeDeg{-360, 360};
inline constexpr NumberRange kUnitRange{0, 1};  // albedos and fractions
// A pixel coordinate (a principal point), 100000 px either side of the image's corner.
inline constexpr NumberRange kPixelRange{-1e5, 1e5};
// A turntable's speed (deg/s) and acceleration (deg/s^2): no turntable of a
// capture rig turns ten times a second.
inline constexpr NumberRange kTurntableSpeedRange{0.01, 3600};
inline constexpr NumberRange kTurntableAccelRange{0.01, 36000};

class ConfigNode {
 public:
  // A regular file of at most kMaxConfigBytes (core/file_util.h
  // ReadFileChunks: a folder, FIFO or device such as /dev/zero is refused).
  static Result<ConfigNode> LoadFile(const std::string& path);
  // `origin` names the text in messages (a file name, "<command line>").
  static Result<ConfigNode> LoadString(const std::string& text, const std::string& origin);

  ConfigNode();
  ~ConfigNode();
  ConfigNode(const ConfigNode&);
  ConfigNode& operator=(const ConfigNode&);

  bool ok() const;
  Status status() const;            // first error recorded anywhere in this document
  const std::string& file() const;  // the file (or origin) the document came from
  const std::string& path() const;  // dotted path of this node: "cameras[1].pose"
  std::string Where() const;        // "file:line:col" of this node
  bool IsMap() const;
  bool Has(std::string_view key) const;
  // The field is present and a scalar (text or a number), not a map or a list.
  bool HasScalar(std::string_view key) const;

  double Number(std::string_view key, NumberRange range = {}) const;
  double Number(std::string_view key, double fallback, NumberRange range = {}) const;
  int Integer(std::string_view key, NumberRange range = {}) const;
  int Integer(std::string_view key, int fallback, NumberRange range = {}) const;
  std::string String(std::string_view key) const;
  std::string String(std::string_view key, const std::string& fallback) const;
  // One of `choices`; the message lists them.
  std::string Choice(std::string_view key, std::initializer_list<const char*> choices,
                     const std::string& fallback = "") const;
  bool Bool(std::string_view key, bool fallback) const;
  // Every element finite and inside `range`; `expected_size` 0 takes any length.
  std::vector<double> Numbers(std::string_view key, size_t expected_size = 0,
                              NumberRange range = {}) const;
  std::vector<std::string> Strings(std::string_view key) const;
  // Three finite numbers, each inside `range`.
  Eigen::Vector3d Vec3(std::string_view key, NumberRange range = {}) const;
  Eigen::Vector3d Vec3(std::string_view key, const Eigen::Vector3d& fallback,
                       NumberRange range = {}) const;

  ConfigNode Child(std::string_view key) const;               // required map
  ConfigNode OptionalChild(std::string_view key) const;       // IsMap() false when absent
  std::vector<ConfigNode> Items(std::string_view key) const;  // required sequence of maps
  std::vector<ConfigNode> OptionalItems(std::string_view key) const;

  // The keys of this map, in file order; empty for a non-map.
  std::vector<std::string> Keys() const;
  // Records an error for any key of this map not in `allowed` (catches typos).
  void AllowOnlyKeys(std::initializer_list<const char*> allowed) const;
  void AllowOnlyKeys(const std::vector<std::string>& allowed) const;
  // Records an error at this node's field `key` (or the node itself for "").
  void Fail(std::string_view key, const std::string& what) const;

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace hairrig
