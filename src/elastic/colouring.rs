//! The order constraints are projected in: a greedy colouring of the particles they move.

/// Orders `constraints` by a greedy colouring of the particles they move (each takes the first
/// colour none of its particles has yet): within a colour no two share a particle, so that
/// one projection need not wait for the one before.
pub(super) fn colour_order<T, const N: usize>(
    constraints: &mut Vec<T>,
    particles: impl Fn(&T) -> [u32; N],
    count: usize,
) {
    // The colours each particle's constraints have taken, as bits.
    let mut taken = vec![0u64; count];
    let mut coloured: Vec<(u32, T)> = constraints
        .drain(..)
        .map(|constraint| {
            let ends = particles(&constraint);
            let used = ends.iter().fold(0u64, |bits, &p| bits | taken[p as usize]);
            let colour = (!used).trailing_zeros().min(63);
            for &p in &ends {
                taken[p as usize] |= 1 << colour;
            }
            (colour, constraint)
        })
        .collect();
    coloured.sort_by_key(|&(colour, _)| colour);
    constraints.extend(coloured.into_iter().map(|(_, constraint)| constraint));
}
