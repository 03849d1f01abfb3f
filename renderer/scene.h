// A scene ready to render: the validated description plus everything built from it (media with
// their compact grids and majorants, lights, Embree surfaces, camera).
#pragma once

#include "auto_strategy.h"

#include "lights.h"
#include "probes.h"
#include "medium.h"
#include "scene_desc.h"
#include "surfaces.h"
#include "tracking.h"

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace candela {

class Camera {
 public:
  explicit Camera(const CameraDesc& desc);
  int width() const { return width_; }
  int height() const { return height_; }
  // A ray through image position (x, y) in pixels; (0, 0) is the top-left corner.
  Ray generate(float x, float y) const;
  // The w x h window of this camera's image at pixel (x0, y0): its pixel (x, y) sees what this
  // camera's pixel (x0 + x, y0 + y) sees (a render region).
  Camera window(int x0, int y0, int w, int h) const;

 private:
  Vec3 origin_, forward_, right_, up_;
  float tanHalf_ = 0.0f, aspect_ = 1.0f;
  int width_ = 0, height_ = 0;
  float offsetX_ = 0.0f, offsetY_ = 0.0f;  // a window's corner in the whole image
  float fullWidth_ = 0.0f, fullHeight_ = 0.0f;
};

// Loads the grids `desc` will need (at its render.frame) into the loader's cache: a later
// Scene::build of the same files and grids does not read them again. Throws like Scene::build.
void prefetchSceneGrids(const SceneDesc& desc);

class Scene {
 public:
  // Loads grids (generating procedural ones into the cache), builds majorants, lights, surfaces.
  // Throws InputError with file/field context; warnings (sanitised voxels) go to `warnings`.
  // `servingProbes` (a live edit's previous probes): with probe guiding they serve at once while the
  // new scene's probes are learned in the background, instead of blocking the build on learning.
  // Any probe set is a valid sampling density (the floor keeps its support complete), so this
  // changes noise, never the converged image.
  static std::shared_ptr<Scene> build(const SceneDesc& desc, std::vector<std::string>* warnings = nullptr,
                                      std::shared_ptr<const ProbeSet> servingProbes = nullptr);

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
  // Some directional light (a sun) shines into the scene: its shafts through thin media are what
  // guided continuations are for (guidedContinuationsApply).
  bool sunLit() const { return sunLit_; }
  // Some medium emits per unit length (EmissionUnits::PerLength).
  bool hasPerLengthEmission() const { return hasPerLengthEmission_; }
  float radius() const { return radius_; }
  Vec3 center() const { return center_; }
  // The box of the volumes and bounded surfaces (ground planes excluded); empty (min > max) when
  // there are none.
  Vec3 boundsMin() const { return boundsMin_; }
  Vec3 boundsMax() const { return boundsMax_; }

  // Coefficients of all media at a world point (outside the hot tracking loop: probes and guided
  // vertices). shares[i] is medium i's mu_s (albedo average); returns their sum.
  struct PointCoefficients {
    float sigmaS = 0.0f, sigmaT = 0.0f, muBar = 0.0f;
    float shares[kMaxMedia] = {};
    // The medium chosen by its share of mu_s for u in [0, 1).
    const Medium& pick(const Scene& scene, float u) const;
  };
  PointCoefficients coefficientsAt(const Vec3& p) const;

  // Applies new strategy settings, rebuilding only what depends on them (majorants, emission
  // grids, light selection; probes are learned when probe guiding turns on or its settings change).
  void setStrategy(const StrategySettings& strategy);
  // Only the adaptive split (StrategySettings::adaptive_split): nothing the scene built depends on
  // it, the renderer reads it per pass.
  void setAdaptiveSplit(int maxSplit) { desc_.strategy.adaptive_split = maxSplit; }
  // setStrategy, or for the preset "auto" as chosen (not yet decided here) the auto strategy's
  // decision (auto_strategy.h). What the viewer and every build call.
  void applyStrategy(const StrategySettings& strategy);
  // What `auto` decided for this scene (null when the strategy is not auto).
  const AutoDecision* autoDecision() const { return autoDecision_ ? &*autoDecision_ : nullptr; }

  // The probe set serving renders now (null without probe guiding). Safe to call while a
  // background relearn runs: the old set keeps serving until the new one is swapped in.
  std::shared_ptr<const ProbeSet> probes() const { return std::atomic_load(&probes_); }
  // Learns probes now (blocking), for the current lights and volumes.
  void learnProbes();
  // Learns probes on a background thread and swaps them in when done; a relearn still running is
  // cancelled first. For live edits of the lights or volume parameters.
  void relearnProbesAsync();
  // Waits for a background relearn to finish.
  void waitForProbes();
  // Moves the camera (a live edit); the probes stay valid (they learn no camera-dependent term).
  void setCamera(const CameraDesc& camera);
  // Applies new render settings (path length, seed, limits): nothing depends on them but the tracer.
  void setRender(const RenderSettings& render) { desc_.render = render; }
  ~Scene();

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
  bool sunLit_ = false;
  bool hasPerLengthEmission_ = false;
  std::optional<AutoDecision> autoDecision_;
  std::shared_ptr<const ProbeSet> probes_;
  std::thread probeThread_;
  std::atomic<bool> cancelProbes_{false};
  float radius_ = 1.0f;
  Vec3 center_{0.0f};
  Vec3 boundsMin_{1.0f}, boundsMax_{-1.0f};
};

// Whether the rays after the camera ray that guiding.secondary_rays names may get a guided sample in
// this scene (guided_segments > 1 still limits how many): from_media_unless_flame_lit leaves them to
// tracking where volumes emit and no sun shines (settings.h). Depends on the scene's lights and
// media, never on a path, so the choice keeps MIS unbiased.
inline bool guidedContinuationsApply(const Scene& scene, const GuidingSettings& g) {
  if (g.guide == DistanceGuide::None || g.guided_segments < 2) return false;
  return g.secondary_rays != SecondaryRays::FromMediaUnlessFlameLit || !scene.hasEmissiveMedia() || scene.sunLit();
}

}  // namespace candela
