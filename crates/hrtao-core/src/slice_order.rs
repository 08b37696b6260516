//! The order of a round's slices (`FrameDesc::lattice`) and what each fills in the first round.
//!
//! A round of L² slices draws each pixel offset of the L×L lattice block once. The slices go coarse to fine
//! (each next offset is the one farthest from those drawn, on the torus of the block), so the pixels drawn so far
//! stay spread evenly and complete square grids on the way: for L = 8 the grids of spacing 8, 4 and 2 after 1, 4
//! and 16 slices (`level`). In the first round of a still image the view shows the cubic B-spline of the finest
//! grid completed (composite.comp `show_level`): smooth at every frame, no single pixels that differ from the
//! blocks around them, and sharper at each level. The grids come by halving: odd lattices (5, 7, 9, 11) complete
//! no grid between L and 1, their held rounds would show the coarse grid throughout, and 10 completes only 5
//! (the viewer takes none of them, `view/slices.rs` `refines_on_the_way`).

/// Squared distance between two offsets of the `lattice`-periodic block (the torus).
fn torus_distance2(a: (u32, u32), b: (u32, u32), lattice: u32) -> u32 {
    let d = |x: u32, y: u32| {
        let d = x.abs_diff(y);
        d.min(lattice - d)
    };
    let (dx, dy) = (d(a.0, b.0), d(a.1, b.1));
    dx * dx + dy * dy
}

/// The offsets of a round's slices in drawing order: (0, 0) first, then each time the offset farthest from the
/// ones before it (ties: the first in row-major order).
fn drawing_order(l: u32) -> Vec<(u32, u32)> {
    let all: Vec<(u32, u32)> = (0..l * l).map(|i| (i % l, i / l)).collect();
    let mut chosen = vec![(0, 0)];
    while chosen.len() < all.len() {
        let next = all
            .iter()
            .filter(|o| !chosen.contains(o))
            .max_by_key(|&&o| {
                let nearest = chosen.iter().map(|&c| torus_distance2(o, c, l)).min().unwrap();
                // The first in row-major order among the farthest.
                (nearest, u32::MAX - (o.1 * l + o.0))
            })
            .copied()
            .unwrap();
        chosen.push(next);
    }
    chosen
}

/// The spacing s of the square grid {(i s, j s)} the first `drawn` offsets of `order` form, when they form
/// exactly one (s divides the lattice), else None.
fn grid_of(order: &[(u32, u32)], drawn: usize, l: u32) -> Option<u32> {
    (1..=l).find(|&s| {
        l.is_multiple_of(s)
            && ((l / s) * (l / s)) as usize == drawn
            && order[..drawn]
                .iter()
                .all(|&(x, y)| x.is_multiple_of(s) && y.is_multiple_of(s))
    })
}

/// A lattice's round, computed once: the offsets in drawing order and the grids they complete.
struct Round {
    offsets: Vec<(u32, u32)>,
    /// Per slice, the spacing of the grid the slices up to it form (`level`).
    levels: Vec<Option<u32>>,
}

fn round(lattice: u32) -> &'static Round {
    static ROUNDS: std::sync::OnceLock<Vec<Round>> = std::sync::OnceLock::new();
    let rounds = ROUNDS.get_or_init(|| {
        (0..=crate::MAX_LATTICE)
            .map(|l| {
                let l = l.max(1);
                let offsets = drawing_order(l);
                let levels = (1..=offsets.len()).map(|n| grid_of(&offsets, n, l)).collect();
                Round { offsets, levels }
            })
            .collect()
    });
    &rounds[lattice.clamp(1, crate::MAX_LATTICE) as usize]
}

/// The offsets of a round's slices in drawing order.
pub fn order(lattice: u32) -> &'static [(u32, u32)] {
    &round(lattice).offsets
}

/// The offset slice `slice` draws (`slice` < lattice²).
pub fn offset(slice: u32, lattice: u32) -> (u32, u32) {
    round(lattice).offsets[slice as usize]
}

/// The spacing s of the square grid {(i s, j s)} the slices 0..=`slice` draw, when they draw exactly one (s
/// divides the lattice; 1 once the round is complete), else None.
pub fn level(slice: u32, lattice: u32) -> Option<u32> {
    round(lattice).levels.get(slice as usize).copied().flatten()
}

/// The finest grid coarser than single pixels (spacing > 1) the slices 0..=`slice` have completed (None before
/// the first).
pub fn finest_grid(slice: u32, lattice: u32) -> Option<u32> {
    let levels = &round(lattice).levels;
    levels[..=(slice as usize).min(levels.len() - 1)]
        .iter()
        .flatten()
        .copied()
        .filter(|&s| s > 1)
        .min()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_LATTICE;

    #[test]
    fn a_round_draws_every_offset_once_coarse_to_fine() {
        for l in 1..=MAX_LATTICE {
            let o = order(l);
            let mut sorted = o.to_vec();
            sorted.sort_by_key(|&(x, y)| (y, x));
            sorted.dedup();
            assert_eq!(sorted.len(), (l * l) as usize, "lattice {l}: {o:?}");
        }
        // Coarse to fine: after (0, 0) the block's centre, then the two half-way offsets.
        assert_eq!(&order(4)[..4], &[(0, 0), (2, 2), (2, 0), (0, 2)]);
        assert_eq!(order(2), &[(0, 0), (1, 1), (1, 0), (0, 1)]);
    }

    #[test]
    fn the_first_round_completes_square_grids_on_the_way() {
        let levels =
            |l: u32| -> Vec<(u32, u32)> { (0..l * l).filter_map(|s| level(s, l).map(|g| (s, g))).collect() };
        assert_eq!(levels(12), vec![(0, 12), (3, 6), (15, 3), (143, 1)]);
        assert_eq!(levels(10), vec![(0, 10), (3, 5), (99, 1)]);
        assert_eq!(levels(9), vec![(0, 9), (80, 1)]);
        assert_eq!(levels(8), vec![(0, 8), (3, 4), (15, 2), (63, 1)]);
        assert_eq!(levels(6), vec![(0, 6), (3, 3), (35, 1)]);
        assert_eq!(levels(4), vec![(0, 4), (3, 2), (15, 1)]);
        assert_eq!(levels(3), vec![(0, 3), (8, 1)]);
        assert_eq!(levels(1), vec![(0, 1)]);
    }
}
