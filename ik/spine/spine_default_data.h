#pragma once
// The embedded default spine description (private to ik/spine).
namespace embody::ik::spine::detail {
extern const char* const kFullSpineJson;        // the 24-site full model
extern const char* const kSimplifiedSitesJson;  // "sites" of the 8-site simplified model
}  // namespace embody::ik::spine::detail
