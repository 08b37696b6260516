#version 460
// Ray-tracing update, step 2: the indirect dispatch size for the queued pixels (one thread). Groups are laid
// out in 2-D so no dimension exceeds 65,535 (the portable limit), e.g. for 3840x2160 screenshots.
#include "common.glsl"

void main() {
    if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
    uint queued = StatsRef(g.stats).counters[STAT_RAY_QUEUE];
    const uint group = WORKGROUP_SIZE * WORKGROUP_SIZE;
    uint groups = (queued + group - 1u) / group;
    UintRef args = UintRef(g.dispatch_args);
    args.v[0] = min(groups, MAX_GROUPS_X);
    args.v[1] = (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X;
    args.v[2] = 1u;
}
