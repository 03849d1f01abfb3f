// A scene ready to render: the validated description plus everything built from it (media with
// their compact grids and majorants, lights, Embree surfaces, camera).
#pragma once

#include "lights.h"
#include "medium.h"
#include "scene_desc.h"
#include "surfaces.h"
#include "tracking.h"

#include <memory>
#include <string>
#include <vector>

namespace candela {

class Camera {
 public:
  explicit Camera(const CameraDesc& desc);
  int width() const { return width_; }
  int height() const { return height_; }
  // A ray through image position (x, y) in pixels; (0, 0) is the top-left corner.
  Ray generate(float x, float y) const;

 private:
  Vec3 origin_, forward_, right_, up_;
  float tanHalf_ = 0.0f, aspect_ = 1.0f;
  int width_ = 0, height_ = 0;
};

class Scene {
 public:
  // Loads grids (generating procedural ones into the cache), builds majorants, lights, surfaces.
  // Throws InputError with file/field context; warnings (sanitised voxels) go to `warnings`.
  static std::shared_ptr<Scene> build(const SceneDesc& desc, std::vector<std::string>* warnings = nullptr);

  const SceneDesc& desc() const { return desc_; }
  const Camera& camera() const { return camera_; }
  const MediaView& media() const { return mediaView_; }
  const std::vector<std::unique_ptr<Medium>>& mediaOwned() const { return media_; }
  const std::vector<Light>& lights() const { return lights_; }
  const LightSampler& lightSampler() const { return lightSampler_; }
  // Emissive volumes sampled as lights; light-sampler entry lights().size() + i is volumeLights()[i].
  const std::vector<const EmissionLight*>& volumeLights() const { return volumeLights_; }
  const Surfaces& surfaces() const { return *surfaces_; }
  const StrategySettings& strategy() const { return desc_.strategy; }
  const RenderSettings& render() const { return desc_.render; }
  bool hasEmissiveMedia() const { return hasEmissiveMedia_; }
  float radius() const { return radius_; }
  Vec3 center() const { return center_; }

  // Applies new strategy settings, rebuilding only what depends on them (majorants).
  void setStrategy(const StrategySettings& strategy);

 private:
  Scene(const SceneDesc& desc);
  SceneDesc desc_;
  Camera camera_;
  std::vector<std::unique_ptr<Medium>> media_;
  MediaView mediaView_;
  std::vector<Light> lights_;
  LightSampler lightSampler_;
  std::vector<const EmissionLight*> volumeLights_;
  void buildLightSampler();
  std::unique_ptr<Surfaces> surfaces_;
  bool hasEmissiveMedia_ = false;
  float radius_ = 1.0f;
  Vec3 center_{0.0f};
};

}  // namespace candela
