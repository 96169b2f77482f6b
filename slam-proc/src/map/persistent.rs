//! A persistent array: a sparse radix tree of reference-counted nodes.
//!
//! Cloning it copies one pointer, so resampling N particles is N pointer copies whatever
//! the maps hold. Writing through [`PersistentArray::get_mut`] copies only the nodes on the
//! path to the slot that other arrays still share (`Arc::make_mut`), so memory grows with
//! what differs between particles, and a write never shows through another clone.

use std::sync::Arc;

/// Index bits per level. Sixteen-way nodes keep the copy on a shared write small (a leaf
/// of sixteen corners is about 2.7 kB) and the tree shallow (three levels to 4096 slots).
const BITS: u32 = 4;
const WIDTH: usize = 1 << BITS;
const MASK: usize = WIDTH - 1;

#[derive(Debug, Clone)]
enum Child<T> {
    Branch(Arc<Branch<T>>),
    Leaf(Arc<Leaf<T>>),
}

#[derive(Debug, Clone)]
struct Branch<T> {
    children: [Option<Child<T>>; WIDTH],
}

impl<T> Default for Branch<T> {
    fn default() -> Self {
        Self {
            children: std::array::from_fn(|_| None),
        }
    }
}

#[derive(Debug, Clone)]
struct Leaf<T> {
    items: [T; WIDTH],
}

impl<T: Default> Default for Leaf<T> {
    fn default() -> Self {
        Self {
            items: std::array::from_fn(|_| T::default()),
        }
    }
}

/// Slots indexed by `usize`, each `T::default()` until written.
#[derive(Debug, Clone)]
pub(crate) struct PersistentArray<T> {
    root: Option<Child<T>>,
    /// Branch levels above the leaves; the capacity is `WIDTH^(levels + 1)`.
    levels: u32,
}

impl<T> Default for PersistentArray<T> {
    fn default() -> Self {
        Self {
            root: None,
            levels: 0,
        }
    }
}

impl<T: Clone + Default> PersistentArray<T> {
    fn capacity_bits(&self) -> u32 {
        (self.levels + 1) * BITS
    }

    /// The slot at `index`; `None` when it was never written (it would be the default).
    pub fn get(&self, index: usize) -> Option<&T> {
        if self.capacity_bits() < usize::BITS && index >> self.capacity_bits() != 0 {
            return None;
        }
        let mut node = self.root.as_ref()?;
        let mut level = self.levels;
        loop {
            match node {
                Child::Branch(branch) => {
                    node = branch.children[(index >> (level * BITS)) & MASK].as_ref()?;
                    level = level.saturating_sub(1);
                }
                Child::Leaf(leaf) => return Some(&leaf.items[index & MASK]),
            }
        }
    }

    /// The slot at `index`, made this array's own: the nodes on its path that are shared
    /// with other arrays are copied first.
    pub fn get_mut(&mut self, index: usize) -> &mut T {
        while self.capacity_bits() < usize::BITS && index >> self.capacity_bits() != 0 {
            if let Some(old) = self.root.take() {
                let mut branch = Branch::default();
                branch.children[0] = Some(old);
                self.root = Some(Child::Branch(Arc::new(branch)));
            }
            self.levels += 1;
        }
        slot_mut(&mut self.root, self.levels, index)
    }

    /// Calls `f` with every written slot, in index order.
    pub fn for_each(&self, mut f: impl FnMut(usize, &T)) {
        if let Some(root) = &self.root {
            visit(root, self.levels, 0, &mut f);
        }
    }

    /// Whether both arrays are the same tree (a clone not written since).
    #[cfg(test)]
    pub fn shares_root_with(&self, other: &Self) -> bool {
        match (&self.root, &other.root) {
            (Some(Child::Branch(a)), Some(Child::Branch(b))) => Arc::ptr_eq(a, b),
            (Some(Child::Leaf(a)), Some(Child::Leaf(b))) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }

    /// How many arrays hold this one's root node.
    #[cfg(test)]
    pub fn root_strong_count(&self) -> usize {
        match &self.root {
            Some(Child::Branch(a)) => Arc::strong_count(a),
            Some(Child::Leaf(a)) => Arc::strong_count(a),
            None => 0,
        }
    }
}

fn slot_mut<T: Clone + Default>(slot: &mut Option<Child<T>>, level: u32, index: usize) -> &mut T {
    let fits = match slot {
        Some(Child::Leaf(_)) => level == 0,
        Some(Child::Branch(_)) => level > 0,
        None => false,
    };
    if !fits {
        // Never written: create the node this level needs.
        *slot = None;
    }
    let child = slot.get_or_insert_with(|| {
        if level == 0 {
            Child::Leaf(Arc::new(Leaf::default()))
        } else {
            Child::Branch(Arc::new(Branch::default()))
        }
    });
    match child {
        Child::Leaf(leaf) => &mut Arc::make_mut(leaf).items[index & MASK],
        Child::Branch(branch) => {
            let branch = Arc::make_mut(branch);
            slot_mut(
                &mut branch.children[(index >> (level * BITS)) & MASK],
                level - 1,
                index,
            )
        }
    }
}

fn visit<T>(node: &Child<T>, level: u32, base: usize, f: &mut impl FnMut(usize, &T)) {
    match node {
        Child::Branch(branch) => {
            for (i, child) in branch.children.iter().enumerate() {
                if let Some(child) = child {
                    visit(
                        child,
                        level.saturating_sub(1),
                        base | (i << (level * BITS)),
                        f,
                    );
                }
            }
        }
        Child::Leaf(leaf) => {
            for (i, item) in leaf.items.iter().enumerate() {
                f(base | i, item);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_back_what_was_written_across_growth() {
        let mut array = PersistentArray::<u32>::default();
        assert_eq!(array.get(0), None);
        for i in [0usize, 5, 9, 63, 64, 511, 4000, 100_000] {
            *array.get_mut(i) = i as u32 + 1;
        }
        for i in [0usize, 5, 9, 63, 64, 511, 4000, 100_000] {
            assert_eq!(array.get(i), Some(&(i as u32 + 1)));
        }
        assert_eq!(array.get(6), Some(&0));
        assert_eq!(array.get(usize::MAX), None);
        let mut seen = Vec::new();
        array.for_each(|i, v| {
            if *v != 0 {
                seen.push(i);
            }
        });
        assert_eq!(seen, vec![0, 5, 9, 63, 64, 511, 4000, 100_000]);
    }

    #[test]
    fn clones_share_until_written_and_writes_stay_private() {
        let mut a = PersistentArray::<u32>::default();
        for i in 0..1000 {
            *a.get_mut(i) = 1;
        }
        let copies: Vec<_> = (0..10).map(|_| a.clone()).collect();
        assert_eq!(a.root_strong_count(), 11);
        assert!(copies.iter().all(|c| c.shares_root_with(&a)));
        let mut b = a.clone();
        *b.get_mut(500) = 7;
        assert!(!b.shares_root_with(&a));
        assert_eq!(a.get(500), Some(&1));
        assert_eq!(b.get(500), Some(&7));
        assert_eq!(b.get(501), Some(&1));
    }
}
