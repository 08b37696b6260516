#version 460
// Resets the per-frame statistics counters and the queues' work-group counts (one thread does it).
#include "common.glsl"

void main() {
    if (gl_GlobalInvocationID.x == 0 && gl_GlobalInvocationID.y == 0) {
        StatsRef stats = StatsRef(g.stats);
        for (uint i = 0; i < STAT_PER_FRAME; ++i) stats.counters[i] = 0u;
        for (uint i = 0; i < RAYS_COUNT; ++i) stats.rays[i] = uint64_t(0);
        // The work groups done of the passes that size a queue (queue_args.glsl).
        UintRef args = UintRef(g.dispatch_args);
        args.v[RAY_ARGS_OFFSET + 3u] = 0u;
        args.v[FILTER_ARGS_OFFSET + 3u] = 0u;
    }
}
