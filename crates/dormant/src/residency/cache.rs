//! The geometry cache: saved static scenes keyed by the set of integrated islands they hold,
//! serving full hits (that exact set), partial hits (the largest saved subset, to which the
//! caller adds the missing islands) and misses, within a memory budget.
//!
//! Eviction is cost-aware (GreedyDual-Size): an entry's priority is the clock value when it
//! was last used plus the build work it saves (its triangles) per byte it keeps alive; the
//! lowest priority goes first and sets the clock. So large entries that save little age out
//! before small ones that save a whole rebuild, and unused entries age out eventually.

use std::collections::BTreeSet;

use crate::physics::IslandId;

/// How a request was served.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CacheOutcome {
    /// An entry holds exactly the requested set.
    Full,
    /// An entry holds a proper, non-empty subset of it.
    Partial,
    /// No entry helps: start from the pristine scene.
    Miss,
}

fn fraction_bucket(fraction: f64) -> usize {
    if fraction >= 1.0 {
        11
    } else if fraction >= 0.99 {
        10
    } else {
        ((fraction * 10.0) as usize).min(9)
    }
}

/// What the cache has done.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CacheStats {
    pub requests: u64,
    pub full: u64,
    pub partial: u64,
    pub miss: u64,
    pub recorded: u64,
    pub(crate) evicted: u64,
    pub(crate) invalidated: u64,
    /// Requests by fraction of requested islands the served entry held ([`Self::FRACTION_BUCKETS`];
    /// an empty request counts as 100%).
    pub fraction_histogram: [u64; 12],
    /// Entries and the bytes they keep alive, after the latest change.
    pub entries: usize,
    pub bytes: usize,
    /// The most entries and bytes held at once so far (measured at every change and whenever
    /// the manager re-measures after a static commit).
    pub(crate) peak_entries: usize,
    pub(crate) peak_bytes: usize,
    /// The budget ([`CacheBudget`]) that `entries` and `bytes` are kept within.
    pub(crate) budget_entries: usize,
    pub(crate) budget_bytes: usize,
}

impl CacheStats {
    /// Buckets of [`Self::fraction_histogram`]: the fraction of the requested islands the
    /// chosen entry already held, in tenths, with the top tenth split at 99%.
    pub const FRACTION_BUCKETS: [&str; 12] = [
        "0-10%", "10-20%", "20-30%", "30-40%", "40-50%", "50-60%", "60-70%", "70-80%", "80-90%", "90-99%",
        "99-100%", "100%",
    ];

    /// Share of requests whose entry held at least 90% but not all of the requested islands
    /// (the paper's "90-99%" class).
    pub fn partial_90_99_fraction(&self) -> f64 {
        let n: u64 = self.fraction_histogram[9] + self.fraction_histogram[10];
        if self.requests == 0 {
            0.0
        } else {
            n as f64 / self.requests as f64
        }
    }
}

/// Bounds of the cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheBudget {
    /// Bytes the entries may keep alive beyond the live scene.
    pub bytes: usize,
    /// Most entries at once (each lookup scans them all).
    pub entries: usize,
}

impl CacheBudget {
    pub const DEFAULT: CacheBudget = CacheBudget { bytes: 512 << 20, entries: 256 };
}

struct Entry<S> {
    key: BTreeSet<IslandId>,
    snapshot: S,
    /// Triangles a from-scratch build of this set would process: the work a hit saves.
    triangles: usize,
    bytes: usize,
    priority: f64,
}

/// An answer to [`GeometryCache::lookup`].
#[derive(Debug)]
pub(crate) struct CacheHit<'a, S> {
    pub outcome: CacheOutcome,
    /// The entry's islands (empty for a miss).
    pub(crate) held: &'a BTreeSet<IslandId>,
    /// The saved scene (`None` for a miss).
    pub snapshot: Option<&'a S>,
}

/// Saved static scenes keyed by their island sets. `S` is the backend's snapshot.
pub(crate) struct GeometryCache<S> {
    budget: CacheBudget,
    entries: Vec<Entry<S>>,
    clock: f64,
    stats: CacheStats,
    empty: BTreeSet<IslandId>,
}

impl<S> GeometryCache<S> {
    pub(crate) fn new(budget: CacheBudget) -> Self {
        let stats = CacheStats {
            budget_entries: budget.entries,
            budget_bytes: budget.bytes,
            ..CacheStats::default()
        };
        Self { budget, entries: Vec::new(), clock: 0.0, stats, empty: BTreeSet::new() }
    }

    pub(crate) fn stats(&self) -> &CacheStats {
        &self.stats
    }

    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.entries.len()
    }

    fn priority(&self, triangles: usize, bytes: usize) -> f64 {
        self.clock + triangles.max(1) as f64 / bytes.max(4096) as f64
    }

    /// Saves `snapshot` as the scene holding exactly `key`, unless an entry for that set
    /// exists. `bytes_of` measures what each entry keeps alive now (entries share structure
    /// with the live scene, so their sizes change as it moves on); entries are evicted until
    /// the budget holds.
    pub(crate) fn record(
        &mut self,
        key: &BTreeSet<IslandId>,
        snapshot: S,
        triangles: usize,
        bytes_of: impl Fn(&S) -> usize,
    ) {
        if let Some(i) = self.entries.iter().position(|e| &e.key == key) {
            self.entries[i].priority = self.priority(self.entries[i].triangles, self.entries[i].bytes);
            return;
        }
        let bytes = bytes_of(&snapshot);
        let priority = self.priority(triangles, bytes);
        self.entries.push(Entry { key: key.clone(), snapshot, triangles, bytes, priority });
        self.stats.recorded += 1;
        self.remeasure(bytes_of);
    }

    /// Measures again what each entry keeps alive (it grows as the live scene moves away from
    /// the entry) and evicts until the budget holds; an entry larger than the whole budget
    /// is not kept.
    pub(crate) fn remeasure(&mut self, bytes_of: impl Fn(&S) -> usize) {
        for e in &mut self.entries {
            e.bytes = bytes_of(&e.snapshot);
        }
        while self.entries.len() > self.budget.entries || self.total_bytes() > self.budget.bytes {
            let victim = (0..self.entries.len())
                .min_by(|&a, &b| self.entries[a].priority.total_cmp(&self.entries[b].priority))
                .expect("non-empty");
            self.clock = self.entries[victim].priority;
            self.entries.swap_remove(victim);
            self.stats.evicted += 1;
        }
        self.refresh_stats();
    }

    fn total_bytes(&self) -> usize {
        self.entries.iter().map(|e| e.bytes).sum()
    }

    fn refresh_stats(&mut self) {
        self.stats.entries = self.entries.len();
        self.stats.bytes = self.total_bytes();
        self.stats.peak_entries = self.stats.peak_entries.max(self.stats.entries);
        self.stats.peak_bytes = self.stats.peak_bytes.max(self.stats.bytes);
    }

    /// The best entry for a static scene holding exactly `request`: an equal set (full hit),
    /// else the largest subset by triangles (partial hit), else a miss. Counts the request.
    pub(crate) fn lookup(&mut self, request: &BTreeSet<IslandId>) -> CacheHit<'_, S> {
        self.stats.requests += 1;
        let best = self
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| e.key.len() <= request.len() && e.key.is_subset(request))
            .max_by_key(|(_, e)| (e.key.len() == request.len(), e.triangles, e.key.len()))
            .map(|(i, _)| i);
        let (outcome, fraction) = match best {
            Some(i) if self.entries[i].key.len() == request.len() => (CacheOutcome::Full, 1.0),
            Some(i) if !self.entries[i].key.is_empty() => {
                (CacheOutcome::Partial, self.entries[i].key.len() as f64 / request.len() as f64)
            }
            _ if request.is_empty() => (CacheOutcome::Miss, 1.0),
            _ => (CacheOutcome::Miss, 0.0),
        };
        match outcome {
            CacheOutcome::Full => self.stats.full += 1,
            CacheOutcome::Partial => self.stats.partial += 1,
            CacheOutcome::Miss => self.stats.miss += 1,
        }
        self.stats.fraction_histogram[fraction_bucket(fraction)] += 1;
        match best.filter(|_| outcome != CacheOutcome::Miss) {
            Some(i) => {
                let priority = self.priority(self.entries[i].triangles, self.entries[i].bytes);
                let e = &mut self.entries[i];
                e.priority = priority;
                CacheHit { outcome, held: &e.key, snapshot: Some(&e.snapshot) }
            }
            None => CacheHit { outcome, held: &self.empty, snapshot: None },
        }
    }

    /// Drops every entry that holds `island` (it woke: those scenes are stale).
    pub(crate) fn invalidate(&mut self, island: IslandId) {
        let before = self.entries.len();
        self.entries.retain(|e| !e.key.contains(&island));
        self.stats.invalidated += (before - self.entries.len()) as u64;
        self.refresh_stats();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(ids: &[u64]) -> BTreeSet<IslandId> {
        ids.iter().map(|&i| IslandId(i)).collect()
    }

    #[test]
    fn full_partial_and_miss() {
        let mut cache = GeometryCache::new(CacheBudget::DEFAULT);
        cache.record(&set(&[1]), "a", 10, |_| 0);
        cache.record(&set(&[1, 2]), "ab", 20, |_| 0);
        assert_eq!(cache.lookup(&set(&[1, 2])).outcome, CacheOutcome::Full);
        let hit = cache.lookup(&set(&[1, 2, 3]));
        assert_eq!((hit.outcome, hit.snapshot), (CacheOutcome::Partial, Some(&"ab")));
        assert_eq!(cache.lookup(&set(&[3])).outcome, CacheOutcome::Miss);
        cache.invalidate(IslandId(2));
        assert_eq!(cache.lookup(&set(&[1, 2, 3])).snapshot, Some(&"a"));
        let s = cache.stats();
        assert_eq!((s.requests, s.full, s.partial, s.miss, s.invalidated), (4, 1, 2, 1, 1));
        assert_eq!(s.fraction_histogram[11], 1);
        assert_eq!(s.fraction_histogram[6], 1, "2 of 3 islands: the 60-70% bucket");
    }

    #[test]
    fn eviction_keeps_the_budget_and_prefers_cheap_bytes() {
        let budget = CacheBudget { bytes: 10_000, entries: 8 };
        let mut cache = GeometryCache::new(budget);
        // "big" keeps 8,000 bytes alive for little work; "small" saves much work in few bytes.
        cache.record(&set(&[1]), 8_000usize, 10, |b| *b);
        cache.record(&set(&[2]), 4_000usize, 1_000_000, |b| *b);
        assert_eq!(cache.len(), 1);
        assert_eq!(cache.lookup(&set(&[2])).outcome, CacheOutcome::Full);
        assert_eq!(cache.stats().evicted, 1);
        for i in 10..30 {
            cache.record(&set(&[i]), 0usize, 1, |b| *b);
        }
        assert!(cache.len() <= budget.entries);
        let s = cache.stats();
        assert_eq!((s.budget_bytes, s.budget_entries), (10_000, 8));
        assert_eq!(s.peak_entries, 8);
        assert_eq!(s.peak_bytes, 8_000, "measured after evictions: the budget always held");
    }

    #[test]
    fn an_entry_larger_than_the_budget_is_not_kept() {
        let mut cache = GeometryCache::new(CacheBudget { bytes: 1_000, entries: 8 });
        cache.record(&set(&[1]), 5_000usize, 1_000_000, |b| *b);
        assert_eq!(cache.len(), 0);
        assert_eq!((cache.stats().evicted, cache.stats().peak_bytes), (1, 0));
    }

    #[test]
    fn remeasuring_evicts_entries_that_grew_past_the_budget() {
        // Entries share structure with the live scene and grow as it moves on: here each
        // holds its size in a cell the "live scene" changes.
        use std::cell::Cell;
        let sizes = [Cell::new(100usize), Cell::new(100), Cell::new(100)];
        let mut cache = GeometryCache::new(CacheBudget { bytes: 1_000, entries: 8 });
        // Entry 0 saves the most work per byte; entry 1 the least.
        for (i, triangles) in [1_000, 10, 20].into_iter().enumerate() {
            cache.record(&set(&[i as u64]), i, triangles, |&j| sizes[j].get());
        }
        assert_eq!((cache.len(), cache.stats().bytes), (3, 300));
        sizes[1].set(600);
        sizes[2].set(600);
        cache.remeasure(|&j| sizes[j].get());
        assert_eq!((cache.len(), cache.stats().evicted), (2, 1));
        assert_eq!(cache.lookup(&set(&[1])).outcome, CacheOutcome::Miss, "entry 1 went");
        assert!(cache.stats().bytes <= 1_000);
        assert_eq!(cache.stats().peak_bytes, 700, "the peak is what the cache kept, after eviction");
    }
}
