//! The order of a round's slices (`FrameDesc::lattice`) and what each fills in the first round.
//!
//! A round of L² slices draws each pixel offset of the L×L lattice block once. The slices go coarse to fine
//! (each next offset is the one farthest from those drawn, on the torus of the block), so the pixels drawn so far
//! stay spread evenly. In the first round of a still image, a slice's pixel also shows in the pixels of later
//! slices it is the nearest drawn pixel to (ties to the latest): every presented frame is the nearest-neighbour
//! image of the pixels drawn so far, blocks that shrink as slices come, never single pixels that differ from a
//! block around them (composite.comp `fill_later`).

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
pub fn order(lattice: u32) -> Vec<(u32, u32)> {
    let l = lattice.max(1);
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

/// The offset slice `slice` draws (`slice` < lattice²).
pub fn offset(slice: u32, lattice: u32) -> (u32, u32) {
    order(lattice)[slice as usize]
}

/// The offsets slice `slice` fills in the first round (bit y L + x): those drawn later whose nearest drawn offset
/// (on the torus, among slices 0..=slice) is this slice's. Ties go to this slice, which is drawn last.
pub fn fill_mask(slice: u32, lattice: u32) -> u64 {
    let l = lattice.max(1);
    let order = order(l);
    let drawn = &order[..=slice as usize];
    let own = order[slice as usize];
    let mut mask = 0u64;
    for &o in &order[slice as usize + 1..] {
        let d = torus_distance2(o, own, l);
        if drawn.iter().all(|&c| torus_distance2(o, c, l) >= d) {
            mask |= 1 << (o.1 * l + o.0);
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_LATTICE;

    #[test]
    fn a_round_draws_every_offset_once_coarse_to_fine() {
        for l in 1..=MAX_LATTICE {
            let o = order(l);
            let mut sorted = o.clone();
            sorted.sort_by_key(|&(x, y)| (y, x));
            sorted.dedup();
            assert_eq!(sorted.len(), (l * l) as usize, "lattice {l}: {o:?}");
        }
        // Coarse to fine: after (0, 0) the block's centre, then the two half-way offsets.
        assert_eq!(&order(4)[..4], &[(0, 0), (2, 2), (2, 0), (0, 2)]);
        assert_eq!(&order(2)[..], &[(0, 0), (1, 1), (1, 0), (0, 1)]);
    }

    /// Replays the first round: each slice writes its offset and fills its mask's offsets. After every slice,
    /// each offset shows a nearest drawn offset (on the torus), and a drawn offset shows itself.
    #[test]
    fn every_first_round_frame_is_the_nearest_neighbour_image() {
        for l in 1..=MAX_LATTICE {
            let order = order(l);
            let mut shown: Vec<Option<(u32, u32)>> = vec![None; (l * l) as usize];
            for (s, &own) in order.iter().enumerate() {
                shown[(own.1 * l + own.0) as usize] = Some(own);
                let mask = fill_mask(s as u32, l);
                for bit in 0..l * l {
                    if mask >> bit & 1 == 1 {
                        assert!(
                            shown[bit as usize] != Some((bit % l, bit / l)),
                            "filled a drawn offset"
                        );
                        shown[bit as usize] = Some(own);
                    }
                }
                let drawn = &order[..=s];
                for bit in 0..l * l {
                    let o = (bit % l, bit / l);
                    let from = shown[bit as usize].expect("every offset shows a drawn one");
                    let nearest = drawn.iter().map(|&c| torus_distance2(o, c, l)).min().unwrap();
                    assert_eq!(
                        torus_distance2(o, from, l),
                        nearest,
                        "lattice {l}, slice {s}, offset {o:?}"
                    );
                }
            }
        }
    }
}
