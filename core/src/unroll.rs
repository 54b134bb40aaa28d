//! Loops written out at compile time, for the small fixed-size solves of the contact steps.
//!
//! [`for_each_index!`] runs a block once per index, with the index a constant. The solves'
//! matrices are arrays of at most 16 × 16; with every index known at compile time the compiler
//! keeps them in registers, where rolled loops over a run-time column index kept them on the
//! stack, and each column's vector loads then waited on the previous column's narrower stores.
//! The written-out loops do the same operations in the same order, so the same bits: an 8 × 8
//! LDLᵀ took about 115 ns rolled and 30 ns written out on the Xeon of stop 69 (a throwaway
//! timing, not kept; what the tiers gained, measured by `tier_cost` and the bench, is in
//! `docs/performance.md`, stop 69). A body guards itself with `if INDEX < N`, which the compiler
//! folds.

/// `for_each_index!(ascending INDEX => { … })` runs the block for INDEX = 0, 1, …, 15;
/// `for_each_index!(descending INDEX => { … })` for INDEX = 15, 14, …, 0. INDEX is a `usize`
/// constant inside the block.
macro_rules! for_each_index {
    (ascending $index:ident => $body:block) => {
        $crate::unroll::for_each_index!(
            @list [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15], $index => $body
        )
    };
    (descending $index:ident => $body:block) => {
        $crate::unroll::for_each_index!(
            @list [15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0], $index => $body
        )
    };
    (@list [$($value:literal),*], $index:ident => $body:block) => {
        $({
            const $index: usize = $value;
            $body
        })*
    };
}

pub(crate) use for_each_index;

/// The largest size the written-out loops cover.
pub(crate) const LARGEST_UNROLLED: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_index_runs_once_in_its_order() {
        let mut ascending = Vec::new();
        for_each_index!(ascending I => {
            ascending.push(I);
        });
        let mut descending = Vec::new();
        for_each_index!(descending I => {
            if I < 5 {
                descending.push(I);
            }
        });
        assert_eq!(ascending, (0..LARGEST_UNROLLED).collect::<Vec<_>>());
        assert_eq!(descending, vec![4, 3, 2, 1, 0]);
    }
}
