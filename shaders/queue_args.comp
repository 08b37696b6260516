#version 460
// Ray-tracing update, step 2: the indirect dispatch size for the queued pixels (one thread).
#include "common.glsl"

void main() {
    if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
    uint queued = StatsRef(g.stats).counters[STAT_RAY_QUEUE];
    const uint group = WORKGROUP_SIZE * WORKGROUP_SIZE;
    UintRef args = UintRef(g.dispatch_args);
    args.v[0] = (queued + group - 1u) / group;
    args.v[1] = 1u;
    args.v[2] = 1u;
}
