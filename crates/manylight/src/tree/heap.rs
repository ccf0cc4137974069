//! The max-heap entry shared by the cuts: the paper's cut ([`super::cut`]) refines the node with
//! the largest error bound, the stochastic cut ([`super::stochastic`]) the node with the largest
//! importance; both keep their frontier in a `BinaryHeap` of [`Keyed`].

use std::cmp::Ordering;

/// A tree node with the key it is refined by and what the cut keeps beside it.
///
/// Ordered by `key` (largest first in a `BinaryHeap`; `f32::total_cmp`, so a NaN key cannot
/// break the heap), ties by the smaller node index first, so the order is total and a cut does
/// not depend on the heap's insertion order. `data` does not take part in the order.
#[derive(Clone, Copy, Debug)]
pub struct Keyed<T = ()> {
    pub key: f32,
    pub node: u32,
    pub data: T,
}

impl Keyed {
    /// An entry with no data.
    #[inline]
    pub fn new(key: f32, node: u32) -> Self {
        Keyed { key, node, data: () }
    }
}

impl<T> PartialEq for Keyed<T> {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl<T> Eq for Keyed<T> {}
impl<T> PartialOrd for Keyed<T> {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl<T> Ord for Keyed<T> {
    fn cmp(&self, o: &Self) -> Ordering {
        self.key.total_cmp(&o.key).then(o.node.cmp(&self.node))
    }
}

#[cfg(test)]
mod tests {
    use super::Keyed;
    use std::collections::BinaryHeap;

    #[test]
    fn pops_largest_key_then_smallest_node() {
        let mut heap = BinaryHeap::new();
        for (key, node) in [(1.0, 5), (3.0, 2), (3.0, 1), (-1.0, 0), (2.0, 7)] {
            heap.push(Keyed { key, node, data: node * 10 });
        }
        let order: Vec<(f32, u32, u32)> =
            std::iter::from_fn(|| heap.pop()).map(|e| (e.key, e.node, e.data)).collect();
        assert_eq!(order, [(3.0, 1, 10), (3.0, 2, 20), (2.0, 7, 70), (1.0, 5, 50), (-1.0, 0, 0)]);
    }

    #[test]
    fn data_does_not_take_part_in_the_order() {
        let a = Keyed { key: 1.0, node: 3, data: 1 };
        let b = Keyed { key: 1.0, node: 3, data: 2 };
        assert_eq!(a, b);
        assert!(Keyed::new(0.5, 9) < Keyed::new(0.5, 8));
    }
}
