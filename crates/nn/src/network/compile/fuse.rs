//! The one fusion pass over the step list: an `ADD` whose sum only the next `PRELU` reads runs
//! as one step.

use crate::network::step::Step;
use crate::ops::Activation;

/// Merges each `ADD` without a fused activation whose sum only the next step, a `PRELU`, reads
/// (and which is not an output) into one [`Step::AddPrelu`]: one pass over memory instead of
/// two, the same values.
pub(super) fn fuse_add_prelu(steps: Vec<Step>, outputs: &[usize]) -> Vec<Step> {
    let mut readers = std::collections::HashMap::<usize, usize>::new();
    for step in &steps {
        for t in step.io().0 {
            *readers.entry(t).or_default() += 1;
        }
    }
    let mut fused = Vec::with_capacity(steps.len());
    let mut it = steps.into_iter().peekable();
    while let Some(step) = it.next() {
        if let Step::Add {
            a,
            b,
            y: sum,
            act: Activation::None,
        } = step
        {
            let only_reader = readers.get(&sum) == Some(&1) && !outputs.contains(&sum);
            if let Some(Step::Prelu { x, .. }) = it.peek() {
                if *x == sum && only_reader {
                    let Some(Step::Prelu { y, alpha, .. }) = it.next() else {
                        unreachable!("peeked")
                    };
                    fused.push(Step::AddPrelu { a, b, y, alpha });
                    continue;
                }
            }
        }
        fused.push(step);
    }
    fused
}
