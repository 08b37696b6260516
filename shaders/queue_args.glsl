// The indirect dispatch size of a queue of pixels, written by the last work group of the pass that fills the
// queue (no dispatch of its own). Groups are laid out in 2-D so no dimension exceeds 65,535 (the portable
// limit), e.g. for 3840x2160 screenshots; a pass dispatched over the queue reads its entry with `queue_entry`
// (common.glsl). The word after a queue's three arguments counts the work groups done (clear.glsl zeroes it);
// the launch size of a ray-tracing pipeline over the same groups follows at QUEUE_TRACE_ARGS.
#ifndef HRTAO_QUEUE_ARGS_GLSL
#define HRTAO_QUEUE_ARGS_GLSL

// Called once by every invocation of the pass, in uniform control flow, after its queue writes: `counter` is
// the queue's statistics counter (STAT_RAY_QUEUE, STAT_FILTER_QUEUE), `o` the arguments' offset in words.
void write_queue_args(uint counter, uint o) {
    controlBarrier(gl_ScopeWorkgroup, gl_ScopeWorkgroup, gl_StorageSemanticsBuffer, gl_SemanticsAcquireRelease);
    if (gl_LocalInvocationIndex != 0u) return;
    uint groups_total = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
    uint done = atomicAdd(UintRef(g.dispatch_args).v[o + 3u], 1u, gl_ScopeDevice, gl_StorageSemanticsBuffer,
                          gl_SemanticsAcquireRelease);
    if (done + 1u != groups_total) return;
    uint queued = atomicLoad(StatsRef(g.stats).counters[counter], gl_ScopeDevice, gl_StorageSemanticsBuffer,
                             gl_SemanticsAcquire);
    const uint group = WORKGROUP_SIZE * WORKGROUP_SIZE;
    uint groups = (queued + group - 1u) / group;
    UintRef args = UintRef(g.dispatch_args);
    args.v[o] = min(groups, MAX_GROUPS_X);
    args.v[o + 1u] = (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X;
    args.v[o + 2u] = 1u;
    // The same groups as a ray-generation launch (recorder.rs, the ray-tracing pipeline backend).
    args.v[o + QUEUE_TRACE_ARGS] = args.v[o] * WORKGROUP_SIZE;
    args.v[o + QUEUE_TRACE_ARGS + 1u] = args.v[o + 1u] * WORKGROUP_SIZE;
    args.v[o + QUEUE_TRACE_ARGS + 2u] = 1u;
}

#endif
