//! Loops written out at compile time, for the small fixed-size solves of the contact steps.
//!
//! [`for_each_index!`] runs a block once per index, with the index a constant. The solves'
//! matrices are arrays of at most 16 × 16; with every index known at compile time the compiler
//! keeps them in registers, where rolled loops over a run-time column index kept them on the
//! stack, and each column's vector loads then waited on the previous column's narrower stores.
//! The written-out loops do the same operations in the same order, so the same bits: an 8 × 8
//! LDLᵀ took about 115 ns rolled and 30 ns written out on the Xeon of stop 69 (a throwaway
//! timing, not kept; what the tiers gained, measured by `tier_cost` and the bench, is in
//! `docs/performance.md`, stop 69).
//!
//! A body guards itself with `if const { INDEX < N }`. The guard is a constant evaluated when the
//! function is instantiated for its `N`, so the code generator emits only the bodies that run;
//! a run-time `if INDEX < N` (folded only later, by LLVM) handed LLVM all 16 bodies of a loop,
//! 256 of two nested loops, each copy of the function. And the fine tier's finishes of two or
//! more crossing points are kept out of line (`modal/nodal.rs`, `finish_out_of_line`), one
//! function per size and vector unit, so that the step is not one function holding every
//! size's kernels: LLVM's time on a function grows faster than its size. The guards change
//! nothing but the compile time; the calls cost the fine tier up to 4 %, measured with what the
//! build saved in `docs/performance.md`, stop 71.

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
