#pragma once
// The embedded default spine description (private to avatar/spine).
namespace embody::spine::detail {
extern const char* const kFullSpineJson;        // the 24-site full model
extern const char* const kSimplifiedSitesJson;  // "sites" of the 8-site simplified model
}  // namespace embody::spine::detail
