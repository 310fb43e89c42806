#include "render/copy_probe.h"

#include <algorithm>
#include <array>
#include <vector>

#include "gpu/kernel.h"
#include "gpu/resources.h"
#include "gpu/timers.h"
#include "shaders/shared/copy_probe.h"
#include "spirv/copy_probe_comp.h"

namespace pic::gpu {

Result<double> computeCopyBandwidth(Context& context, const CopyProbeParams& params) {
    if (params.bytes == 0 || params.bytes % 16 != 0 || params.bytes / 16 > UINT32_MAX)
        return fail(ErrorCode::InvalidInput,
                    "copy probe bytes must be a positive multiple of 16 "
                    "below 64 GiB, got {}",
                    params.bytes);
    if (params.copiesPerSubmission < 1 || params.submissions < 2 || params.maxGroups < 1)
        return fail(ErrorCode::InvalidInput,
                    "copy probe needs ≥ 1 copy per submission, ≥ 2 "
                    "submissions and ≥ 1 workgroup, got {}, {} and {}",
                    params.copiesPerSubmission, params.submissions, params.maxGroups);
    KernelLayout layout;
    layout.bindings.assign(2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    layout.pushBytes = sizeof(CopyProbePush);
    PIC_TRY_ASSIGN(Kernel kernel,
                   Kernel::create(context, kSpirvCopyProbeComp, layout, "copy probe"));
    PIC_TRY_ASSIGN(Buffer source, Buffer::create(context, params.bytes, 0, MemoryUse::Device,
                                                 "copy probe source"));
    PIC_TRY_ASSIGN(Buffer target, Buffer::create(context, params.bytes, 0, MemoryUse::Device,
                                                 "copy probe target"));
    std::vector<uint32_t> words(params.bytes / 4);
    for (size_t i = 0; i < words.size(); ++i) words[i] = uint32_t(i * 2654435761u);
    PIC_TRY(context.upload(source, words.data(), params.bytes));
    const std::array<BindingResource, 2> resources = {BindingResource::storage(0, source),
                                                      BindingResource::storage(1, target)};
    PIC_TRY_ASSIGN(VkDescriptorSet set, kernel.makeSet(resources));
    PIC_TRY_ASSIGN(PassTimer timer, PassTimer::create(context, 1));

    const CopyProbePush push{uint32_t(params.bytes / 16), 0, 0, 0};
    // By default enough groups to fill any GPU, few enough for the dispatch limit.
    const uint32_t groups = std::min(groupsFor(push.words, kCopyProbeGroup), params.maxGroups);
    std::vector<double> rates;
    for (int s = 0; s < params.submissions; ++s) {
        PIC_TRY(context.submit(
            [&](VkCommandBuffer cmd) {
                timer.begin(cmd, "copy");
                for (int c = 0; c < params.copiesPerSubmission; ++c) {
                    kernel.dispatch(cmd, set, &push, groups);
                    computeBarrier(cmd);  // one copy after another, not overlapping
                }
            },
            &timer));
        std::vector<std::pair<std::string, double>> ms;
        PIC_TRY(timer.collect(ms));
        if (s > 0 && !ms.empty() && ms[0].second > 0.0)
            rates.push_back(double(params.copiesPerSubmission) * double(params.bytes) /
                            (ms[0].second * 1e-3));
    }
    std::vector<uint32_t> copied(words.size());
    PIC_TRY(context.download(target, copied.data(), params.bytes));
    if (const auto [a, b] = std::mismatch(words.begin(), words.end(), copied.begin());
        a != words.end())
        return fail(ErrorCode::Internal,
                    "copy probe on \"{}\" copied word {} as {:#x}, expected {:#x}",
                    context.deviceName(), a - words.begin(), *b, *a);
    if (rates.empty())
        return fail(ErrorCode::Internal, "\"{}\" gave no copy timestamps", context.deviceName());
    std::nth_element(rates.begin(), rates.begin() + rates.size() / 2, rates.end());
    return rates[rates.size() / 2];
}

}  // namespace pic::gpu
