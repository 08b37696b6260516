#version 460
// The indirect dispatch size for the pixels of a queue (one thread): push.x is the queue's counter
// (STAT_RAY_QUEUE for the ray-tracing update, STAT_FILTER_QUEUE for the filter), push.y the arguments' offset
// in words. Groups are laid out in 2-D so no dimension exceeds 65,535 (the portable limit), e.g. for 3840x2160
// screenshots; a pass reads its entry with `queue_entry` (common.glsl).
#include "common.glsl"

void main() {
    if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
    uint queued = StatsRef(g.stats).counters[push.x];
    const uint group = WORKGROUP_SIZE * WORKGROUP_SIZE;
    uint groups = (queued + group - 1u) / group;
    UintRef args = UintRef(g.dispatch_args);
    uint o = push.y;
    args.v[o] = min(groups, MAX_GROUPS_X);
    args.v[o + 1u] = (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X;
    args.v[o + 2u] = 1u;
}
