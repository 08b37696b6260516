// Resets the per-frame statistics counters and the queues' work-group counts (queue_args.glsl): one thread of
// primary visibility does it (no pass of its own; nothing before primary visibility reads them in a frame).
#ifndef HRTAO_CLEAR_GLSL
#define HRTAO_CLEAR_GLSL

void clear_frame_counters() {
    if (THREAD_ID.x == 0 && THREAD_ID.y == 0) {
        StatsRef stats = StatsRef(g.stats);
        for (uint i = 0; i < STAT_PER_FRAME; ++i) stats.counters[i] = 0u;
        for (uint i = 0; i < RAYS_COUNT; ++i) stats.rays[i] = uint64_t(0);
        UintRef args = UintRef(g.dispatch_args);
        args.v[RAY_ARGS_OFFSET + 3u] = 0u;
        args.v[FILTER_ARGS_OFFSET + 3u] = 0u;
    }
}

#endif
