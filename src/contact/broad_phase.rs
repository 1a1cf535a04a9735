//! Broad phase: sweep and prune over x of bounding boxes inflated by the search distance.
//! The sort order is kept between steps, so the insertion sort runs in near-linear time.
use super::Mobility;
use crate::geometry::BlockGeometry;

#[derive(Debug, Default)]
pub struct BroadPhase {
    order: Vec<usize>,
    boxes: Vec<[f64; 4]>,
    pairs: Vec<(usize, usize)>,
}

impl BroadPhase {
    /// Recompute the candidate pairs (a < b); pairs of two immobile blocks are skipped.
    pub fn update(&mut self, geoms: &[BlockGeometry], mobility: &[Mobility], search: f64) {
        let n = geoms.len();
        self.boxes.clear();
        for g in geoms {
            let (lo, hi) = g.bounds();
            self.boxes
                .push([lo.x - search, hi.x + search, lo.y - search, hi.y + search]);
        }
        if self.order.len() != n {
            self.order = (0..n).collect();
        }
        // Insertion sort: O(n) when the order barely changed since the last step.
        for k in 1..n {
            let mut m = k;
            while m > 0 && self.boxes[self.order[m - 1]][0] > self.boxes[self.order[m]][0] {
                self.order.swap(m - 1, m);
                m -= 1;
            }
        }
        self.pairs.clear();
        for (k, &a) in self.order.iter().enumerate() {
            let ba = self.boxes[a];
            for &b in &self.order[k + 1..] {
                let bb = self.boxes[b];
                if bb[0] > ba[1] {
                    break;
                }
                if bb[2] > ba[3] || ba[2] > bb[3] {
                    continue;
                }
                if mobility[a] != Mobility::Free && mobility[b] != Mobility::Free {
                    continue;
                }
                self.pairs.push((a.min(b), a.max(b)));
            }
        }
        // Deterministic contact order whatever the sweep order was.
        self.pairs.sort_unstable();
    }

    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }
}
