// rtog::CRTreeOccupancyGridMap: the R-tree occupancy grid as an mrpt::maps::CMetricMap, so that
// MRPT's applications (icp-slam, rbpf-slam, pf-localization, observations2map, ...) can use it
// from any CMultiMetricMap .ini with `rtreeOccupancyGrid_count=1`. See doc/mrpt_map.md.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussian.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/mrpt/insertion_options.h"
#include "rtog/mrpt/map_types.h"
#include "rtog/mrpt/prior_map_options.h"
#include "rtog/mrpt/view_options.h"

namespace mrpt::obs {
class CObservation2DRangeScan;
class CObservationRange;
}

namespace rtog {

namespace detail {
struct SensorPoints;  // src/sensor_points.hpp
}
namespace pose_sigma {
struct SigmaPose;  // src/pose_sigma.hpp
}
namespace mrpt_grid3d {
struct RaySet;  // src/mrpt_grid3d.hpp
}

class CRTreeOccupancyGridMap : public mrpt::maps::CMetricMap {
  DEFINE_SERIALIZABLE(CRTreeOccupancyGridMap, rtog)

 public:
  /// Options for inserting observations ([<prefix>_insertOpts]; rtog/mrpt/insertion_options.h).
  using TInsertionOptions = RTreeInsertionOptions;

  /// COccupancyGridMap2D's methods and numbers (doc/mrpt_map.md: 0 meant the likelihood field
  /// before, and now means lmMeanInformation as in MRPT's grid).
  enum TLikelihoodMethod {
    lmMeanInformation = 0,
    lmRayTracing = 1,
    lmConsensus = 2,
    lmCellsDifference = 3,
    lmLikelihoodField_Thrun = 4,
    lmLikelihoodField_II = 5,
    lmConsensusOWA = 6
  };

  /// Options for computeObservationLikelihood ([<prefix>_likelihoodOpts]).
  struct TLikelihoodOptions : public mrpt::config::CLoadableOptions {
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
    void validate() const;

    /// One of COccupancyGridMap2D's seven methods. (Default: lmLikelihoodField_Thrun)
    TLikelihoodMethod likelihoodMethod{lmLikelihoodField_Thrun};
    /// Std. dev. [m] of the likelihood field's Gaussian. (Default: 0.35)
    float LF_stdHit{0.35f};
    /// Weight of the Gaussian term. (Default: 0.95)
    float LF_zHit{0.95f};
    /// Weight of the uniform term (divided by LF_maxRange). (Default: 0.05)
    float LF_zRandom{0.05f};
    /// Beams longer than this [m] are ignored. (Default: 81)
    float LF_maxRange{81.0f};
    /// Use one of every N beams. (Default: 5)
    uint32_t LF_decimation{5};
    /// Distances to the nearest occupied cell are capped here [m]. (Default: 0.3)
    float LF_maxCorrsDistance{0.3f};
    /// Sum squared distances instead of Gaussian log terms (faster, unnormalized). (Default: false)
    bool LF_useSquareDist{false};
    /// Cache the distance to the nearest occupied cell per lattice cell. (Default: true)
    bool enableLikelihoodCache{true};
    /// Use one of every N beams in ray tracing. (Default: 10)
    int32_t rayTracing_decimation{10};
    /// Std. dev. [m] of the measured vs. ray-traced range. (Default: 1.0)
    float rayTracing_stdHit{1.0f};
    // COccupancyGridMap2D's keys for the methods it computes on the 2D view (same defaults).
    bool LF_alternateAverageMethod{false};  ///< [LF, 2D view] average, not product. (Default: false)
    float MI_exponent{2.5f};                ///< [MI] (Default: 2.5)
    uint32_t MI_skip_rays{10};              ///< [MI] (Default: 10)
    float MI_ratio_max_distance{1.5f};      ///< [MI] (Default: 1.5)
    bool rayTracing_useDistanceFilter{true};  ///< [rayTracing, 2D view] (Default: true)
    int32_t consensus_takeEachRange{1};     ///< [Consensus] (Default: 1)
    float consensus_pow{5.0f};              ///< [Consensus] (Default: 5)
    std::vector<float> OWA_weights = std::vector<float>(100, 0.01f);  ///< [OWA] (Default: 100 x 0.01)
    /// Planar 2D scans are scored by MRPT's COccupancyGridMap2D code on gridView() (exactly the
    /// stock grid's value); false: by the native 3D LF / ray tracing. (Default: true)
    bool scanLikelihoodOnGridView{true};
  };

  /// The 2D view's band, ICP's band and how getVisualizationInto draws (rtog/mrpt/view_options.h).
  using TGridViewOptions = RTreeGridViewOptions;
  using TMatchingOptions = RTreeMatchingOptions;
  using TRenderingOptions = RTreeRenderingOptions;

  explicit CRTreeOccupancyGridMap(double resolution = 0.10);
  CRTreeOccupancyGridMap(double resolution, const TInsertionOptions& io);

  TInsertionOptions insertionOptions;
  TLikelihoodOptions likelihoodOptions;
  TGridViewOptions gridViewOptions;
  TMatchingOptions matchingOptions;
  TRenderingOptions renderingOptions;

  /// The wrapped core map. Changing it directly does not invalidate the caches: call
  /// notifyMapChanged() afterwards.
  OccupancyMap& map() { return map_; }
  const OccupancyMap& map() const { return map_; }
  void notifyMapChanged();
  double resolution() const { return map_.resolution(); }
  /// Fuses another robot's (sensor's, day's) map into this one by the independent opinion pool,
  /// `other` placed at `pose` (its frame in this map's): OccupancyMap::fuse. Returns its counts.
  InsertStats fuse(const CRTreeOccupancyGridMap& other, const mrpt::poses::CPose3D& pose = {});

  using mrpt::maps::CMetricMap::insertObservation;
  /// Inserts `obs` taken from the uncertain robot pose `pose`. With insertionOptions.poseUncertainty
  /// the update is the mixture of the sensor model's probabilities over the sigma points of the
  /// pose covariance (rtog::sigmaPoints: its mean and covariance exactly; doc/pose-uncertainty.md);
  /// a zero covariance, or poseUncertainty off, inserts at the mean exactly as
  /// insertObservation(obs, pose.mean) does. Throws std::invalid_argument for a covariance that is
  /// not one, changing nothing.
  bool insertObservation(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3DPDFGaussian& pose);
  /// The same for a planar pose (x, y, phi): z, pitch and roll are certain.
  bool insertObservation(const mrpt::obs::CObservation& obs, const mrpt::poses::CPosePDFGaussian& pose);
  /// CMetricMap::loadFromSimpleMap, but each frame's pose PDF (as a Gaussian: its mean and
  /// covariance) goes to insertObservation above, so that poseUncertainty = on uses the
  /// simplemap's covariances. MRPT's own method is not virtual: called through a CMetricMap (as
  /// MRPT's apps do), the frames are inserted at their mean poses.
  void loadFromSimpleMap(const mrpt::maps::CSimpleMap& sm) { loadFromProbabilisticPosesAndObservations(sm); }
  void loadFromProbabilisticPosesAndObservations(const mrpt::maps::CSimpleMap& sm);

  /// Beams of an observation in the map frame; false for an unsupported type.
  bool extractBeams(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose,
                    ObservationBeams& out, bool forInsertion) const;

  /// mrpt_grid: the geometry a COccupancyGridMap2D would have now (2D scans grow it as they
  /// grow the grid); setGridFrame() sets it as the grid's setSize() would, on an empty map.
  const TGridFrame2D& gridFrame() const { return frame_; }
  void setGridFrame(float x_min, float x_max, float y_min, float y_max);

  /// mrpt_grid, a 3D section: the COccupancyGridMap3D whose cells observations step (undefined
  /// without one, doc/mrpt_map.md). setGridFrame3D() sets it as that grid's constructor would
  /// (corners, resolution), on an empty map; throws std::invalid_argument for a bad extent.
  const TGridFrame3D& gridFrame3D() const { return frame3d_; }
  void setGridFrame3D(const mrpt::math::TPoint3D& corner_min, const mrpt::math::TPoint3D& corner_max,
                      float resolution);
  /// COccupancyGridMap3D's API on that grid (a defined frame; std::logic_error otherwise): the
  /// probability that cell (cx, cy, cz) is free (0.5 unknown or outside), as getCellFreeness;
  /// one ray's steps, as insertRay (the end occupied; `endIsOccupied` is ignored there too);
  /// every `decimation`-th point of `pts` (map frame) a ray, as insertPointCloud (which ignores
  /// `maxValidRange` too); the cells as voxels, as getAsOctoMapVoxels.
  float getCellFreeness(unsigned cx, unsigned cy, unsigned cz) const;
  void insertRay(const mrpt::math::TPoint3D& sensor, const mrpt::math::TPoint3D& end, bool endIsOccupied = true);
  void insertPointCloud(const mrpt::math::TPoint3D& sensor, const mrpt::maps::CPointsMap& pts,
                        float maxValidRange = std::numeric_limits<float>::max());
  void getAsOctoMapVoxels(mrpt::opengl::COctoMapVoxels& gl_obj) const;

  /// What inserting a 2D scan in the mrpt_grid preset did, for a 2D view to follow it.
  struct GridScanUpdate {
    float grow[4];  ///< the rectangle the grid grew to (x_min, x_max, y_min, y_max)
    std::vector<OccupancyMap::StepRun> runs;  ///< the cells stepped, in order (lattice keys)
    std::vector<float> after;                 ///< each step's cell value after it
  };
  /// Inserts a 2D scan with COccupancyGridMap2D's rule (mrpt_grid preset); false where the grid
  /// would insert nothing. `update`, if given, receives what changed.
  bool insertGridScan(const mrpt::obs::CObservation2DRangeScan& scan, const mrpt::poses::CPose3D& robotPose,
                      GridScanUpdate* update = nullptr);

  /// A CObservationRange's readings as cones in the map frame (doc/sonar.md): each at
  /// robotPose + its own sensorPose, about its own axis; a reading at or beyond
  /// maxSensorDistance has no echo (free up to it, if considerInvalidRangesAsFreeSpace), one
  /// beyond maxDistanceInsertion is cut there; `invalid` counts the readings dropped (no
  /// finite positive range, or no echo and not taken as free). Throws std::invalid_argument for
  /// an aperture outside [0, pi] or a maxSensorDistance not positive and finite.
  std::vector<ConeReading> sonarReadings(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& robotPose,
                                         std::size_t& invalid) const;
  /// Inserts a CObservationRange: octomap preset, by OccupancyMap::insertCones with
  /// sonarConeWeighting; mrpt_grid, by COccupancyGridMap2D's whole steps in the grid's layer.
  bool insertSonar(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& robotPose);

  /// Figures of the last and of all insertions.
  InsertStats lastInsertStats, totalInsertStats;
  std::size_t invalidRangesSkipped{0};  ///< over all insertions

  /// Occupied cell centres (cached until the map changes).
  const mrpt::maps::CSimplePointsMap& occupiedCellCenters() const;

  // ---- CMetricMap ---------------------------------------------------------------------
  bool isEmpty() const override;
  void determineMatching2D(const mrpt::maps::CMetricMap* otherMap, const mrpt::poses::CPose2D& otherMapPose,
                           mrpt::tfest::TMatchingPairList& correspondences,
                           const mrpt::maps::TMatchingParams& params,
                           mrpt::maps::TMatchingExtraResults& extraResults) const override;
  void determineMatching3D(const mrpt::maps::CMetricMap* otherMap, const mrpt::poses::CPose3D& otherMapPose,
                           mrpt::tfest::TMatchingPairList& correspondences,
                           const mrpt::maps::TMatchingParams& params,
                           mrpt::maps::TMatchingExtraResults& extraResults) const override;
  float compute3DMatchingRatio(const mrpt::maps::CMetricMap* otherMap, const mrpt::poses::CPose3D& otherMapPose,
                               const mrpt::maps::TMatchingRatioParams& params) const override;
  float squareDistanceToClosestCorrespondence(float x0, float y0) const override;
  void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
  void getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const override;
  std::string asString() const override;
  const mrpt::maps::CSimplePointsMap* getAsSimplePointsMap() const override { return &occupiedCellCenters(); }

  /// Writes `file` as a gzip-compressed CArchive holding this map; loadFromFile reads it back.
  void saveToFile(const std::string& file) const;
  /// The map a file holds. Throws std::runtime_error naming the file if it cannot be read, is
  /// damaged, holds another class, or has bytes after the map.
  static std::shared_ptr<CRTreeOccupancyGridMap> loadFromFile(const std::string& file);
  /// The same from a stream, read forward only (a pipe works): gzip-compressed or plain CArchive.
  static std::shared_ptr<CRTreeOccupancyGridMap> loadFromStream(std::istream& in);

  /// Log-likelihood of beams already in the map frame (used by computeObservationLikelihood).
  double beamsLikelihood(const ObservationBeams& b) const;

  // ---- COccupancyGridMap2D's API on the 2D view (see doc/mrpt_map.md, "2D view") ----------
  /// The band's cells as a COccupancyGridMap2D (same resolution, cell k covers [k*res,(k+1)*res)),
  /// built on first use and kept until the map or the band changes. Shared: its methods that
  /// fill MRPT's mutable caches (likelihoods) must not run concurrently on it.
  std::shared_ptr<const mrpt::maps::COccupancyGridMap2D> gridView() const;
  void computeEntropy(mrpt::maps::COccupancyGridMap2D::TEntropyInfo& info) const;
  void laserScanSimulator(mrpt::obs::CObservation2DRangeScan& inout_Scan, const mrpt::poses::CPose2D& robotPose,
                          float threshold = 0.6f, size_t N = 361, float noiseStd = 0, unsigned int decimation = 1,
                          float angleNoiseStd = 0) const;
  void sonarSimulator(mrpt::obs::CObservationRange& inout_observation, const mrpt::poses::CPose2D& robotPose,
                      float threshold = 0.5f, float rangeNoiseStd = 0.f, float angleNoiseStd = 0.f) const;
  void simulateScanRay(double x, double y, double angle_direction, float& out_range, bool& out_valid,
                       double max_range_meters, float threshold_free = 0.4f, double noiseStd = 0,
                       double angleNoiseStd = 0) const;
  void getAsImage(mrpt::img::CImage& img, bool verticalFlip = false, bool forceRGB = false,
                  bool tricolor = false) const;
  bool saveAsBitmapFile(const std::string& file) const;
  float computeClearance(float x, float y, float maxSearchDistance) const;
  double getArea() const;  ///< of the 2D view [m^2]
  struct TCellCounts {
    std::size_t free{0}, occupied{0}, unknown{0};  ///< P(free) > 0.5, < 0.5, == 0.5
  };
  TCellCounts gridViewCellCounts() const;
  /// Replaces the map with the grid's known cells, one z-layer (the one holding z = 0, moved
  /// into the band) at the grid's resolution, values exact (-l/16); widens clampingMin/Max
  /// if the grid holds more certain cells.
  void loadFromGrid(const mrpt::maps::COccupancyGridMap2D& grid);
  /// As COccupancyGridMap2D::loadFromBitmapFile, then loadFromGrid.
  bool loadFromBitmapFile(const std::string& file, float resolution,
                          const mrpt::math::TPoint2D& origin = mrpt::math::TPoint2D(
                              std::numeric_limits<double>::max(), std::numeric_limits<double>::max()));
  /// A .gridmap / .gridmap.gz (a CArchive of a COccupancyGridMap2D, gzip or not), then loadFromGrid.
  bool loadFromGridmapFile(const std::string& file);
  /// Replaces the map with a prior (doc/priors.md): loadFromGrid's cells, each drawn towards 0.5
  /// by `confidence` in (0.5, 1] (TPriorMapOptions::priorConfidence). Later observations update
  /// it by the normal update; cells they do not reach keep it exactly; clear() returns to it.
  void loadPrior(const mrpt::maps::COccupancyGridMap2D& grid, double confidence);
  /// The prior `o` names, read from its file. Throws std::invalid_argument for bad options and
  /// std::runtime_error naming the file if it cannot be read as the kind its name says.
  void loadPrior(const TPriorMapOptions& o);
  /// Metres along `direction` from `origin` to the first occupied cell (native 3D); nullopt if
  /// none within maxRange.
  std::optional<double> castRay(const mrpt::math::TPoint3D& origin, const mrpt::math::TVector3D& direction,
                                double maxRange) const;
  /// Metres from p to the nearest occupied cell (native 3D); nullopt if none within maxDistance.
  std::optional<double> nearestObstacleDistance(const mrpt::math::TPoint3D& p, double maxDistance) const;

  MAP_DEFINITION_START(CRTreeOccupancyGridMap)
  /// Cell edge length [m], as in COccupancyGridMap2D. (Default: 0.10)
  double resolution{0.10};
  /// mrpt_grid: the initial extent of the grid the 2D scans follow, as COccupancyGridMap2D's.
  /// (Default: -10, 10, -10, 10; in a 3D section COccupancyGridMap3D's -5, 5, -5, 5)
  float min_x{-10.0f}, max_x{10.0f}, min_y{-10.0f}, max_y{10.0f};
  /// A 3D section (the _creationOpts has min_z or max_z): the COccupancyGridMap3D's z extent; its
  /// other keys and defaults are then that grid's (doc/mrpt_map.md). (Default: -5, 5)
  float min_z{-5.0f}, max_z{5.0f};
  bool grid3D{false};
  rtog::CRTreeOccupancyGridMap::TInsertionOptions insertionOpts;
  rtog::CRTreeOccupancyGridMap::TLikelihoodOptions likelihoodOpts;
  rtog::CRTreeOccupancyGridMap::TGridViewOptions gridViewOpts;  ///< read from _creationOpts
  rtog::CRTreeOccupancyGridMap::TMatchingOptions matchingOpts;
  rtog::TPriorMapOptions priorOpts;  ///< read from _creationOpts; loaded when the map is created
  /// A bad .ini value found while loading, raised when the map is created: MRPT leaks the
  /// definition if loading itself throws.
  std::string loadError;
  MAP_DEFINITION_END(CRTreeOccupancyGridMap)

 private:
  void internal_clear() override;
  bool internal_insertObservation(const mrpt::obs::CObservation& obs,
                                  const std::optional<const mrpt::poses::CPose3D>& robotPose) override;
  double internal_computeObservationLikelihood(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPose3D& takenFrom) const override;
  bool internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const override;

  /// Re-creates the (empty) core map if the insertion options changed its parameters; throws
  /// std::logic_error if they changed while the map holds cells.
  void syncParams();
  /// loadFromGrid with the values drawn towards 0.5 by `confidence` (1: exact).
  void loadGridLayer(const mrpt::maps::COccupancyGridMap2D& grid, double confidence);
  /// Planar 2D scans and sonar readings scored on the 2D view (see scanLikelihoodOnGridView);
  /// nullopt: not so.
  std::optional<double> gridViewLikelihood(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& pose) const;
  struct GridView;  // CRTreeOccupancyGridMap_grid2d.hpp
  /// The view, grown (rebuilt) first if it does not cover `need` (x0, y0, x1, y1 [m]).
  std::shared_ptr<GridView> gridViewShared(const double* need = nullptr) const;
  double likelihoodField(const ObservationBeams& b) const;
  double rayTracing(const ObservationBeams& b) const;
  /// The likelihood field's parameters, folded once per scan.
  struct FieldParams {
    double inv2var, zHit, zRandomTerm;
    float cap;
    bool squareDist;
    bool operator==(const FieldParams& o) const {
      return inv2var == o.inv2var && zHit == o.zHit && zRandomTerm == o.zRandomTerm && cap == o.cap &&
             squareDist == o.squareDist;
    }
  };
  /// Occupied cell centres within matchingOptions' height band (cached until the map or the
  /// band changes; the whole cloud when the band holds every cell).
  const mrpt::maps::CSimplePointsMap& occupiedCellCentersForMatching2D() const;
  /// The log-likelihood term of an end point at p: its distance to the nearest occupied cuboid
  /// (capped) through the field's Gaussian-plus-uniform mixture. With the cache on, per lattice
  /// cell, as COccupancyGridMap2D's precomputed field. The caller holds caches_->mutex.
  float fieldTermLocked(const Eigen::Vector3d& p, const FieldParams& f) const;
  /// An observation's beams in its sensor's frame (not a CObservationRange: see sonar::endPoints),
  /// decimated for insertion or for the likelihood; false for an unsupported type.
  bool sensorPoints(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, bool forInsertion,
                    detail::SensorPoints& sp) const;
  /// Sensor-frame points decoded by `decode`, or the last ones if `key` (a fingerprint of
  /// everything they depend on: the observation's data, geometry and decimation) is the last one's.
  template <class Decode>
  void localPointsCached(std::uint64_t key, Decode&& decode, std::vector<Eigen::Vector3f>& pts,
                         std::size_t& invalid) const;

  /// Derived data (likelihood-field terms, point clouds, decoded points, the 2D view), defined
  /// in src/ so that this header needs no hash map. Copies share the 2D view's tiles (copy on
  /// write) and start without the rest (rebuilt on demand). Guarded by Caches::mutex.
  struct Caches;
  /// cos/sin of the beam angles of the last 2D scan geometry (defined with Caches).
  struct ScanAngles;
  /// Owns the caches; copies and assignments share the tiles and drop the rest (see Caches).
  /// Declared before the cells, so destroyed after them (the last map trims the heap: src/).
  class CachesHolder {
   public:
    CachesHolder();
    ~CachesHolder();
    CachesHolder(const CachesHolder&);
    CachesHolder& operator=(const CachesHolder&);
    Caches* operator->() const { return p_.get(); }
   private:
    std::unique_ptr<Caches> p_;
  };

  mutable CachesHolder caches_;
  OccupancyMap map_;
  TGridFrame2D frame_;
  TGridFrame3D frame3d_;
  /// What clear() returns to (MRPT's apps clear a map before they fill it): the cells and frame
  /// loadPrior() made, shared by copies; none otherwise. Not serialized.
  struct Prior;
  std::shared_ptr<const Prior> prior_;

  /// cos/sin of the scan's beam angles, from the cache when the geometry is the last one's.
  std::shared_ptr<const ScanAngles> scanAngles(const mrpt::obs::CObservation2DRangeScan& scan) const;
  /// An observation of a 3D section from weighted poses (one of weight 1: a certain pose) by
  /// COccupancyGridMap3D's rule; false for a type without points.
  bool insertGrid3D(const mrpt::obs::CObservation& obs, const std::vector<pose_sigma::SigmaPose>& poses);
  /// Rays into the 3D grid (std::logic_error naming `what` without one; src/mrpt_grid3d.hpp).
  void stepRays(const char* what, const std::vector<mrpt_grid3d::RaySet>& sets);
  /// After a grid scan: the view's tiles, if kept (followsGridScans), take its steps; the other
  /// caches are dropped as by notifyMapChanged().
  void followGridScan(const GridScanUpdate& upd);
  bool followsGridScans() const;
  /// A 2D scan of a 2D section in the mrpt_grid preset from weighted poses (src/grid_graded.hpp).
  bool insertGradedScan(const mrpt::obs::CObservation2DRangeScan& scan, const std::vector<pose_sigma::SigmaPose>& poses,
                        GridScanUpdate* update = nullptr);
  /// lmLikelihoodField_Thrun of a planar scan on the view's tiles (made from the map first if
  /// none are kept); nullopt where the tiles cannot stand for the view (see the .cpp).
  std::optional<double> tilesLikelihood(const mrpt::obs::CObservation2DRangeScan& scan,
                                        const mrpt::poses::CPose3D& pose) const;
};

}  // namespace rtog
