#pragma once
/// The bake flags of ARCHITECTURE.md §5, registered on any CLI11 command
/// (`picbake bake`, `picbench bake`), so every tool spells them the same way.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bake/bake.h"

namespace pic {

/// Raw flag values; `toOptions` turns them into BakeOptions after parsing.
class BakeOptionFlags {
public:
    /// Adds --surfels, --links, --bands, --chroma-bands, --grid-cell, --lightmap-texel,
    /// --link-mode, --hierarchy, --link-samples, --exposure-rays, --link-reads, --link-cut,
    /// --relax and --seed to `command`.
    void addTo(CLI::App& command);
    /// The options the user set; unset ones stay empty so the bake picks defaults.
    BakeOptions toOptions() const;
    /// The flags the user gave, as given ("--links", "32", …), to pass on to picbake.
    std::vector<std::string> toArgs() const;

private:
    BakeOptions mOptions;
    uint32_t mSurfels = 0, mLinks = 0, mBands = 0, mChromaBands = 0;
    float mGridCell = 0.0f, mLightmapTexel = 0.0f;
    std::string mLinkMode = "rtp", mHierarchy = "visible", mLinkReads = "visible",
                mLinkCut = "error", mGridCaches = "surfaces";
    CLI::Option* mSurfelsOption = nullptr;
    CLI::Option* mLinksOption = nullptr;
    CLI::Option* mBandsOption = nullptr;
    CLI::Option* mChromaOption = nullptr;
    CLI::Option* mGridOption = nullptr;
    CLI::Option* mTexelOption = nullptr;
    std::vector<const CLI::Option*> mAdded;  ///< every option addTo added, in order
};

}  // namespace pic
