// The scene's fixed-name settings as enums, each with one name table: the scene file's parser,
// the error messages, the reference (snowbake help scene) and the manifest all take the names
// from here, so a name is spelt once.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/parameters.h"
#include "core/phenomena/timeline_edits.h"

namespace snow {

enum class SceneMode { Season, Occlusion, Mesh };             // mode
enum class SunMethod { Auto, Horizon, Embree };               // precompute.sun_method
enum class BackendChoice { Cpu, Cuda, Auto };                 // run.backend, --backend
enum class ImageFormat { Exr, Tiff };                         // outputs.format
enum class TileConvention { None, Unreal, Unity, Grid };      // outputs.tiles.convention
// terrain.format; Builtin is what a terrain.builtin source resolves to, not a terrain.format value.
enum class TerrainFormat { Auto, Dem, Heightmap, Raw, Mesh, Builtin };
enum class TerrainCoordinates { Auto, Geographic, Metres };  // terrain.coordinates
enum class ByteOrder { Little, Big };                         // terrain.byte_order
enum class EventType { Snowfall, Avalanche, Skier };          // events.type
enum class UpAxis { Z, Y };                                   // terrain.up_axis, occluders.up_axis: a mesh's up
enum class FrameWriting { Paused, Beside, AfterSeason };     // run.frame_writing (bake/frame_timing.h)
// season.avalanche_flow: AvalancheFlow (core/parameters.h)

// EnumNames<E>::table: every value of E with its name, in the order the reference lists them.
template <class E>
struct EnumNames;

template <>
struct EnumNames<SceneMode> {
  static constexpr std::array<std::pair<SceneMode, std::string_view>, 3> table{
      {{SceneMode::Season, "season"}, {SceneMode::Occlusion, "occlusion"}, {SceneMode::Mesh, "mesh"}}};
};
template <>
struct EnumNames<SunMethod> {
  static constexpr std::array<std::pair<SunMethod, std::string_view>, 3> table{
      {{SunMethod::Auto, "auto"}, {SunMethod::Horizon, "horizon"}, {SunMethod::Embree, "embree"}}};
};
template <>
struct EnumNames<BackendChoice> {
  static constexpr std::array<std::pair<BackendChoice, std::string_view>, 3> table{
      {{BackendChoice::Cpu, "cpu"}, {BackendChoice::Cuda, "cuda"}, {BackendChoice::Auto, "auto"}}};
};
template <>
struct EnumNames<ImageFormat> {
  static constexpr std::array<std::pair<ImageFormat, std::string_view>, 2> table{
      {{ImageFormat::Exr, "exr"}, {ImageFormat::Tiff, "tiff"}}};
};
template <>
struct EnumNames<TileConvention> {
  static constexpr std::array<std::pair<TileConvention, std::string_view>, 4> table{
      {{TileConvention::None, "none"}, {TileConvention::Unreal, "unreal"}, {TileConvention::Unity, "unity"}, {TileConvention::Grid, "grid"}}};
};
template <>
struct EnumNames<TerrainFormat> {
  static constexpr std::array<std::pair<TerrainFormat, std::string_view>, 6> table{
      {{TerrainFormat::Auto, "auto"}, {TerrainFormat::Dem, "dem"}, {TerrainFormat::Heightmap, "heightmap"}, {TerrainFormat::Raw, "raw"},
       {TerrainFormat::Mesh, "mesh"}, {TerrainFormat::Builtin, "builtin"}}};
};
template <>
struct EnumNames<TerrainCoordinates> {
  static constexpr std::array<std::pair<TerrainCoordinates, std::string_view>, 3> table{
      {{TerrainCoordinates::Auto, "auto"}, {TerrainCoordinates::Geographic, "geographic"}, {TerrainCoordinates::Metres, "metres"}}};
};
template <>
struct EnumNames<ByteOrder> {
  static constexpr std::array<std::pair<ByteOrder, std::string_view>, 2> table{{{ByteOrder::Little, "little"}, {ByteOrder::Big, "big"}}};
};
template <>
struct EnumNames<UpAxis> {
  static constexpr std::array<std::pair<UpAxis, std::string_view>, 2> table{{{UpAxis::Z, "z"}, {UpAxis::Y, "y"}}};
};
template <>
struct EnumNames<AvalancheFlow> {
  static constexpr std::array<std::pair<AvalancheFlow, std::string_view>, 2> table{
      {{AvalancheFlow::Pipes, "pipes"}, {AvalancheFlow::ShallowWater, "shallow_water"}}};
};
template <>
struct EnumNames<FrameWriting> {
  static constexpr std::array<std::pair<FrameWriting, std::string_view>, 3> table{
      {{FrameWriting::Paused, "paused"}, {FrameWriting::Beside, "beside"}, {FrameWriting::AfterSeason, "after_season"}}};
};
template <>
struct EnumNames<EventType> {
  static constexpr std::array<std::pair<EventType, std::string_view>, 3> table{
      {{EventType::Snowfall, "snowfall"}, {EventType::Avalanche, "avalanche"}, {EventType::Skier, "skier"}}};
};
template <>
struct EnumNames<EditOp> {  // edits.op (core/phenomena/timeline_edits.h)
  static constexpr std::array<std::pair<EditOp, std::string_view>, 4> table{
      {{EditOp::Add, "add"}, {EditOp::Remove, "remove"}, {EditOp::Set, "set"}, {EditOp::Move, "move"}}};
};

template <class E>
std::string enumName(E value) {
  for (const auto& [v, name] : EnumNames<E>::table)
    if (v == value) return std::string(name);
  return "?";
}

template <class E>
std::optional<E> enumFromName(std::string_view name) {
  for (const auto& [v, n] : EnumNames<E>::table)
    if (n == name) return v;
  return std::nullopt;
}

template <class E>
std::vector<std::string> enumNames() {
  std::vector<std::string> names;
  for (const auto& entry : EnumNames<E>::table) names.emplace_back(entry.second);
  return names;
}

}  // namespace snow
