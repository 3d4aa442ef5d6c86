//! Buffer planning: which activation buffer ("slot") each computed tensor lives in, from the
//! tensors' lifetimes over the step list.

use super::step::Step;

/// Liveness-based buffer sharing: each computed tensor gets a slot that no tensor alive at the
/// same time uses (best fit among the free slots, grown when needed). The graph input and
/// outputs keep their slots for the whole run. Returns the slot of each tensor and each slot's
/// length.
pub(super) fn allocate_slots(
    steps: &[Step],
    len_of: &[usize],
    input: usize,
    outputs: &[usize],
) -> (Vec<usize>, Vec<usize>) {
    let n = len_of.len();
    let mut last_use = vec![0usize; n];
    for (k, step) in steps.iter().enumerate() {
        for t in step.io().0 {
            last_use[t] = k;
        }
    }
    let pinned = |t: usize| t == input || outputs.contains(&t);
    let mut slot_of = vec![0usize; n];
    let mut slot_len = vec![len_of[input]];
    let mut free: Vec<usize> = Vec::new();
    for (k, step) in steps.iter().enumerate() {
        let (reads, y) = step.io();
        let need = len_of[y];
        let best = free
            .iter()
            .enumerate()
            .filter(|&(_, &s)| slot_len[s] >= need)
            .min_by_key(|&(_, &s)| slot_len[s])
            .map(|(i, _)| i)
            .or_else(|| (!free.is_empty()).then(|| free.len() - 1));
        let s = match best {
            Some(i) => free.swap_remove(i),
            None => {
                slot_len.push(0);
                slot_len.len() - 1
            }
        };
        slot_len[s] = slot_len[s].max(need);
        slot_of[y] = s;
        for t in reads {
            if last_use[t] == k && !pinned(t) && !free.contains(&slot_of[t]) {
                free.push(slot_of[t]);
            }
        }
    }
    (slot_of, slot_len)
}
