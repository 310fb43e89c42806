#include "bake/bake_options_cli.h"

namespace pic {

void BakeOptionFlags::addTo(CLI::App& command) {
    const size_t first = command.get_options().size();
    mSurfelsOption = command.add_option("--surfels", mSurfels, "surfel count nS (default: from scene area and extent)");
    mLinksOption = command.add_option("--links", mLinks, "links per cache nL (default 128)");
    mBandsOption = command.add_option("--bands", mBands, "SH bands for luma lY, 1-8 (default 3)");
    mChromaOption = command.add_option("--chroma-bands", mChromaBands, "SH bands for chroma lC <= lY (default 2)");
    mGridOption = command.add_option("--grid-cell", mGridCell, "grid cell size in metres (default: largest extent / 16)");
    command.add_option("--grid-caches", mGridCaches,
                       "where grid caches go: surfaces (only where surfaces too small for the "
                       "light map read them), volume (everywhere near geometry: dynamic objects "
                       "near surfaces) or space (every free grid vertex: dynamic objects "
                       "anywhere); default surfaces")
        ->check(CLI::IsMember({"surfaces", "volume", "space"}));
    mTexelOption = command.add_option("--lightmap-texel", mLightmapTexel,
                                      "light-map texel size in metres (default: about 8k texels over the scene's area)");
    command.add_option("--link-mode", mLinkMode, "sh or rtp (default rtp)")->check(CLI::IsMember({"sh", "rtp"}));
    command.add_option("--hierarchy", mHierarchy,
                       "visible (clusters that cannot see each other stay apart), agglomerative "
                       "(the paper's) or kdtree (default visible)")
        ->check(CLI::IsMember({"visible", "agglomerative", "kdtree"}));
    command.add_option(
        "--link-samples", mOptions.linkSamples,
        "visibility rays per node estimate while choosing a cache's links (default 16)");
    command.add_option("--link-final-samples", mOptions.linkFinalSamples,
                       "visibility rays of each linked node's final estimate (default 64)");
    command.add_option("--exposure-rays", mOptions.exposureRays,
                       "rays per surfel that weight a node's flux towards its exposed surfels; 0: the "
                       "paper's uniform node radiance (default 64)");
    command.add_option("--sky-rays", mOptions.skyRays,
                       "rays per surfel and per cache for the sky transfer (how much of the sky "
                       "each sees, for sky lights); 0: none, and light sets with a sky are "
                       "refused (default 256)");
    command.add_option("--link-reads", mLinkReads,
                       "whose flux a link reads: visible (the smallest part of the linked node "
                       "holding what the cache sees) or node (the paper's; default visible)")
        ->check(CLI::IsMember({"visible", "node"}));
    command.add_option("--link-cut", mLinkCut,
                       "how a cache's links are chosen: error (refine the node with the largest "
                       "visible solid angle times radius, the bound on its model's error) or "
                       "solid-angle (the paper's; default error)")
        ->check(CLI::IsMember({"error", "solid-angle"}));
    command.add_option("--relax", mOptions.relaxIterations, "surfel relaxation iterations (default 4)");
    command.add_option("--seed", mOptions.seed, "random seed (default 1)");
    const std::vector<CLI::Option*> all = command.get_options();
    mAdded.assign(all.begin() + std::ptrdiff_t(first), all.end());
}

std::vector<std::string> BakeOptionFlags::toArgs() const {
    std::vector<std::string> args;
    for (const CLI::Option* option : mAdded) {
        if (option->count() == 0) continue;
        args.push_back("--" + option->get_single_name());
        for (const std::string& value : option->results()) args.push_back(value);
    }
    return args;
}

BakeOptions BakeOptionFlags::toOptions() const {
    BakeOptions options = mOptions;
    if (*mSurfelsOption) options.surfels = mSurfels;
    if (*mLinksOption) options.links = mLinks;
    if (*mBandsOption) options.bandsY = mBands;
    if (*mChromaOption) options.bandsC = mChromaBands;
    if (*mGridOption) options.gridCell = mGridCell;
    if (*mTexelOption) options.lightmapTexel = mLightmapTexel;
    options.gridCaches = mGridCaches == "space"    ? GridCaches::Space
                         : mGridCaches == "volume" ? GridCaches::Volume
                                                   : GridCaches::Surfaces;
    options.linkMode = mLinkMode == "sh" ? LinkMode::Sh : LinkMode::Rtp;
    options.hierarchy = mHierarchy == "kdtree"          ? HierarchyMethod::KdTree
                        : mHierarchy == "agglomerative" ? HierarchyMethod::Agglomerative
                                                        : HierarchyMethod::Visible;
    options.linkReads = mLinkReads == "node" ? LinkReads::Node : LinkReads::Visible;
    options.linkCut = mLinkCut == "solid-angle" ? LinkCut::SolidAngle : LinkCut::ErrorBound;
    return options;
}

}  // namespace pic
