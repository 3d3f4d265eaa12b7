// A 2D scan of a class derived from CObservation2DRangeScan, for what MRPT computes only for such.
#pragma once

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

namespace rtog_test {

/// A CObservation2DRangeScan of a class of its own (MRPT's IS_CLASS compares the exact runtime
/// class): MRPT 2.5.8's lmConsensusOWA computes its value only for such a scan (see
/// MapGrid2D.ConsensusOWAOfADerivedScanEqualsStockGrid). MRPT's points maps insert only the exact
/// class too, so the scan's cached points are built here as OWA builds them for the scan (a
/// CSimplePointsMap of every point, minDistBetweenLaserPoints = -1), not copied from `s`.
class DerivedScan : public mrpt::obs::CObservation2DRangeScan {
 public:
  explicit DerivedScan(const mrpt::obs::CObservation2DRangeScan& s) : mrpt::obs::CObservation2DRangeScan(s) {
    auto pts = mrpt::maps::CSimplePointsMap::Create();
    pts->insertionOptions.minDistBetweenLaserPoints = -1;
    pts->insertObservation(s);
    m_cachedMap = pts;
  }
  const mrpt::rtti::TRuntimeClassId* GetRuntimeClass() const override { return &kClassId; }
  static const mrpt::rtti::TRuntimeClassId* baseClass() { return CLASS_ID(mrpt::obs::CObservation2DRangeScan); }
  static inline const mrpt::rtti::TRuntimeClassId kClassId{"rtog_test::DerivedScan", nullptr, &DerivedScan::baseClass};
};

}  // namespace rtog_test
