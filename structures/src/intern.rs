//! Hash-consing over word arrays, shared by the DAG builds (`svdag`'s nodes, `tree64.dag`'s child
//! spans): a table of entry ids keyed by the entry's words, so that equal entries are stored once
//! and met again by id. The table holds ids only; the caller owns the words and says where an
//! entry's words are ([`intern`]'s `entry`), so each structure keeps its own compact store.

use std::hash::BuildHasher;

use foldhash::fast::FixedState;
use hashbrown::HashTable;

/// The fixed-seed foldhash every store uses (no layout ever depends on hash values: entries are
/// ordered by first occurrence).
const HASHER: FixedState = FixedState::with_seed(0x5dac_0001);

#[inline(always)]
pub(crate) fn hash(key: &[u32]) -> u64 {
    HASHER.hash_one(key)
}

/// What [`intern`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interned {
    /// An equal entry is stored under this id.
    Found(u32),
    /// None was: `new_id` is now in the table, and the caller must store the key's words under it.
    New(u32),
}

/// Looks `key` up in `table`, whose ids name entries whose words `entry(id)` returns; inserts
/// `new_id` if no stored entry equals `key`. `entry` is also how the table rehashes as it grows.
#[inline]
pub(crate) fn intern<'w>(
    table: &mut HashTable<u32>,
    key: &[u32],
    new_id: u32,
    entry: impl Fn(u32) -> &'w [u32],
) -> Interned {
    match table.entry(hash(key), |&id| entry(id) == key, |&id| hash(entry(id))) {
        hashbrown::hash_table::Entry::Occupied(e) => Interned::Found(*e.get()),
        hashbrown::hash_table::Entry::Vacant(e) => {
            e.insert(new_id);
            Interned::New(new_id)
        }
    }
}

/// Reserves room for `additional` more ids without rehashing while they are inserted.
pub(crate) fn reserve<'w>(table: &mut HashTable<u32>, additional: usize, entry: impl Fn(u32) -> &'w [u32]) {
    table.reserve(additional, |&id| hash(entry(id)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_keys_get_one_id_and_different_keys_their_own() {
        let mut words: Vec<u32> = Vec::new();
        let mut starts: Vec<u32> = vec![0];
        let mut table = HashTable::new();
        let mut ids = Vec::new();
        let keys: [&[u32]; 6] = [&[1, 2], &[3], &[1, 2], &[1, 2, 3], &[3], &[]];
        for key in keys {
            let id = starts.len() as u32 - 1;
            let found = {
                let (w, s) = (&words, &starts);
                intern(&mut table, key, id, |i| &w[s[i as usize] as usize..s[i as usize + 1] as usize])
            };
            match found {
                Interned::Found(id) => ids.push(id),
                Interned::New(id) => {
                    words.extend_from_slice(key);
                    starts.push(words.len() as u32);
                    ids.push(id);
                }
            }
        }
        assert_eq!(ids, [0, 1, 0, 2, 1, 3]);
        assert_eq!(words, [1, 2, 3, 1, 2, 3]);
    }
}
