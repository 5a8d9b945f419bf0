//! Files parsed once per process and shared by the instances that read them.
//!
//! # Why
//! An instance reads its tap bank (2.9 MB for `learned.taps`, 3.4 MB over conicities) and the
//! design response (0.3 MB of TOML) at initialization, and parsing them cost most of an
//! instance's start: about 10 ms and 5 ms of the 20 ms the bindings took per record
//! (2026-11-28, `perf`), against some 30 ms of stepping for a 1 km pass. A fleet or Monte-Carlo run
//! makes one instance per pass, in the same process; they all read the same files.
//!
//! # Rule
//! A parsed file is kept under a key (its path, or a built-in file's name) with the bytes it was
//! parsed from. An instance reads the file's bytes as before; where they equal the kept ones,
//! it shares the kept value (read-only: an `Arc`), else it parses them and keeps the result in
//! place of the oldest entry beyond [`KEPT`]. Comparing the bytes, not a time stamp or a size,
//! means a file rewritten between two instances is read again whatever its clock says. A file
//! that does not parse is not kept: every instance reports it. The lock is held only to look up
//! and to insert; two instances that miss at once both parse, and the second's result is kept.
//!
//! # Lifetime
//! Where instances come and go through a host that may unload the library (the FMU), they
//! belong to a [`Group`]: when its last member goes, the group empties the caches, so a library
//! whose instances are all freed holds no parsed file (an importer that unloads it loses no
//! memory; valgrind sees none lost). Instances that live at once share; one after another, each
//! parses again. Without a group (the bindings, the studies: a process that never unloads the
//! library) the caches keep what they parsed.

use std::sync::{Arc, Mutex};

/// Entries kept per cache: the shipped banks and a user's own fit or two. Their memory stays
/// while a [`Group`]'s member lives, or without a group until the process ends (resident, with
/// the design response: 16 MB for `learned.taps`, 35 MB for `learned-conicity.taps`).
pub const KEPT: usize = 4;

/// One kind of parsed file, keyed by path or name.
pub struct Cache<T> {
    entries: Mutex<Vec<Entry<T>>>,
}

struct Entry<T> {
    key: String,
    bytes: Vec<u8>,
    value: Arc<T>,
}

impl<T> Cache<T> {
    /// An empty cache (a `static`).
    pub const fn new() -> Cache<T> {
        Cache {
            entries: Mutex::new(Vec::new()),
        }
    }

    /// The value parsed from `bytes` under `key`: the kept one where it was parsed from the same
    /// bytes, else `parse(bytes)`, kept when it succeeds.
    pub fn get_or_parse<E>(
        &self,
        key: &str,
        bytes: &[u8],
        parse: impl FnOnce(&[u8]) -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        if let Some(v) = self
            .lock()
            .iter()
            .find(|e| e.key == key && e.bytes == bytes)
        {
            return Ok(v.value.clone());
        }
        let value = Arc::new(parse(bytes)?);
        let mut entries = self.lock();
        entries.retain(|e| e.key != key);
        if entries.len() >= KEPT {
            entries.remove(0);
        }
        entries.push(Entry {
            key: key.to_string(),
            bytes: bytes.to_vec(),
            value: value.clone(),
        });
        Ok(value)
    }

    /// Forgets every entry (the values stay with whoever holds them), and the list's own
    /// memory: nothing of the cache is left allocated.
    pub fn clear(&self) {
        *self.lock() = Vec::new();
    }

    /// The entries, also after a thread panicked holding the lock: the list is replaced whole
    /// or not at all under it, so it is never half written.
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Entry<T>>> {
        self.entries.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Users of some caches, and what empties them when the last user goes ([module docs](self)).
pub struct Group {
    users: Mutex<usize>,
    release: fn(),
}

impl Group {
    /// A group whose last member's going calls `release` (a `static`).
    pub const fn new(release: fn()) -> Group {
        Group {
            users: Mutex::new(0),
            release,
        }
    }

    /// A new member, until dropped.
    pub fn join(&'static self) -> Member {
        *self.count() += 1;
        Member { group: self }
    }

    fn count(&self) -> std::sync::MutexGuard<'_, usize> {
        self.users.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// One user of a [`Group`]'s caches: an instance, or a copy of one (a saved FMU state).
pub struct Member {
    group: &'static Group,
}

impl Clone for Member {
    fn clone(&self) -> Member {
        self.group.join()
    }
}

impl Drop for Member {
    fn drop(&mut self) {
        let mut n = self.group.count();
        *n = n.saturating_sub(1);
        // Emptied under the count's lock: no member joins halfway through.
        if *n == 0 {
            (self.group.release)();
        }
    }
}

impl std::fmt::Debug for Member {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Member")
    }
}

impl<T> Default for Cache<T> {
    fn default() -> Self {
        Cache::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    fn parse_count(
        cache: &Cache<String>,
        key: &str,
        bytes: &[u8],
        calls: &Cell<usize>,
    ) -> Arc<String> {
        cache
            .get_or_parse(key, bytes, |b| {
                calls.set(calls.get() + 1);
                String::from_utf8(b.to_vec())
            })
            .unwrap()
    }

    #[test]
    fn the_same_bytes_are_parsed_once_and_other_bytes_again() {
        let cache = Cache::new();
        let calls = Cell::new(0);
        let a = parse_count(&cache, "f", b"one", &calls);
        let b = parse_count(&cache, "f", b"one", &calls);
        assert!(Arc::ptr_eq(&a, &b) && calls.get() == 1);
        // The file rewritten under the same name, same length: read again.
        let c = parse_count(&cache, "f", b"two", &calls);
        assert_eq!((c.as_str(), calls.get()), ("two", 2));
        // The same bytes under another key are another file.
        let d = parse_count(&cache, "g", b"two", &calls);
        assert!(!Arc::ptr_eq(&c, &d) && calls.get() == 3);
        // What a caller holds is untouched by what replaces it in the cache.
        assert_eq!(a.as_str(), "one");
    }

    #[test]
    fn the_group_empties_its_caches_when_its_last_member_goes() {
        static CACHE: Cache<String> = Cache::new();
        static GROUP: Group = Group::new(|| CACHE.clear());
        let calls = Cell::new(0);
        let a = GROUP.join();
        let b = a.clone();
        parse_count(&CACHE, "f", b"x", &calls);
        drop(a);
        parse_count(&CACHE, "f", b"x", &calls);
        assert_eq!(calls.get(), 1, "kept while a member lives");
        drop(b);
        assert_eq!(
            CACHE.lock().capacity(),
            0,
            "emptied, its memory too, when the last member went"
        );
        let _c = GROUP.join();
        parse_count(&CACHE, "f", b"x", &calls);
        assert_eq!(calls.get(), 2);
    }

    #[test]
    fn a_failed_parse_is_not_kept_and_the_oldest_entry_goes_first() {
        let cache: Cache<String> = Cache::new();
        let calls = Cell::new(0);
        for _ in 0..2 {
            let e = cache.get_or_parse("bad", &[0xff], |b| {
                calls.set(calls.get() + 1);
                String::from_utf8(b.to_vec())
            });
            assert!(e.is_err());
        }
        assert_eq!(calls.get(), 2, "every reader reports a bad file");
        let first = parse_count(&cache, "k0", b"0", &calls);
        for i in 1..KEPT {
            parse_count(&cache, &format!("k{i}"), b"x", &calls);
        }
        let kept = calls.get();
        assert!(Arc::ptr_eq(
            &first,
            &parse_count(&cache, "k0", b"0", &calls)
        ));
        parse_count(&cache, "new", b"y", &calls);
        assert_eq!(calls.get(), kept + 1);
        // k0 was used most recently but entered first: the cache keeps insertion order.
        parse_count(&cache, "k0", b"0", &calls);
        assert_eq!(
            calls.get(),
            kept + 2,
            "the oldest entry was dropped for the new one"
        );
    }
}
