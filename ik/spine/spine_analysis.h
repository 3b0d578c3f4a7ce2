#pragma once
// Reading a solved spine back as anatomy: per-site swing (s_x flexion, s_y bending) and torsion,
// and the two shape measures of the isolated-spine experiment.
#include <Eigen/Core>

#include <vector>

#include "ik/model.h"
#include "ik/spine/spine_description.h"
#include "ik/spine/spine_model.h"

namespace embody::ik::spine {

struct SiteMotion {
  double s_x = 0.0;      // swing about the site's lateral axis: flexion (+ forward), radians
  double s_y = 0.0;      // swing about its forward axis: lateral bending (+ to the left), radians
  double torsion = 0.0;  // rotation about the spine axis (+ front to the left), radians
};

// Per site, from the configuration q of a model built by appendSpine. Coupled sites read their
// swing / revolute dofs; a ball joint is split swing-then-twist about the spine axis (R = S T).
std::vector<SiteMotion> siteMotion(const ik::Model& model, const Eigen::VectorXd& q, const SpineJoints& joints);

// For each region and each swing component, every site carrying it has its value divided by its
// limit in the value's direction; the standard deviation across the region's sites. The largest
// over regions and components: 0 = every level bends in proportion to its mobility.
double swingSpread(const SpineDescription& description, const SpineJoints& joints,
                   const std::vector<SiteMotion>& motion);

// Sign changes of torsion from one torsion-carrying site to the next inside a region, summed
// over regions; |torsion| below `epsilon` (radians) counts as no sign.
int torsionSignChangesWithinRegions(const SpineDescription& description, const SpineJoints& joints,
                                    const std::vector<SiteMotion>& motion, double epsilon = 1e-4);

// Sign changes of torsion across the region boundaries: the last torsion-carrying site of a
// region against the first of the next (the first counts only when above `epsilon`).
int torsionSignChangesBetweenRegions(const SpineDescription& description, const SpineJoints& joints,
                                     const std::vector<SiteMotion>& motion, double epsilon = 1e-4);

// The largest |swing component / its limit in that direction| over the sites (1 = at a limit).
double maxNormalisedSwing(const SpineDescription& description, const SpineJoints& joints,
                          const std::vector<SiteMotion>& motion);

// Per vertebra: the torsion of the site whose joint carries it (carrierSite), shared in
// proportion to the vertebra's axial range, so the vertebrae of a site add up to its torsion.
std::vector<double> vertebraTorsion(const SpineDescription& description, const SpineJoints& joints,
                                    const std::vector<SiteMotion>& motion);

}  // namespace embody::ik::spine
