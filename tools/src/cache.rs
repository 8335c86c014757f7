//! Memory traffic and a texel cache model for a hardware texture unit.
//!
//! The lookups report every read as a bit range of the storage they read ([`Access`]; see
//! `texsat::Counter::read_at`). Two models turn that trace into what a memory system sees:
//!
//! * [`Bus`]: a bus of `width` bits fetching aligned bursts of `burst` bus words. A read of bits
//!   `[a, a + n)` costs the bursts it overlaps; per sample and per frame, the bus words and bytes
//!   fetched with no cache.
//! * [`Cache`]: a set-associative cache (`size` bytes, `line` bytes per line, `ways` ways, LRU),
//!   in front of the same memory: a read touches every line its bits overlap; a miss fetches the
//!   line. Hit rate and bytes fetched from memory per sample.
//!
//! Regions (the table, the texture, a pyramid) are separate memories: [`Access::region`] is
//! placed at a base address of its own, far apart, so they never share a line.

/// One read: `bits` bits from bit `offset` of storage `region`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Access {
    /// Which storage (0: the table or layout words, 1: the texture, 2..: other structures).
    pub region: u8,
    /// Bit offset in that storage.
    pub offset: u64,
    /// Bits read (all channels together).
    pub bits: u32,
}

/// Byte address of `region`'s first byte: regions 2^40 bytes apart.
fn base(region: u8) -> u64 {
    u64::from(region) << 40
}

/// The byte range `[first, last]` an access touches.
fn byte_range(a: &Access) -> (u64, u64) {
    let first = base(a.region) + a.offset / 8;
    let last = base(a.region) + (a.offset + u64::from(a.bits.max(1)) - 1) / 8;
    (first, last)
}

/// A bus of `width` bits moving aligned bursts of `burst` bus words, no cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bus {
    /// Bus width in bits (32 or 64).
    pub width: u32,
    /// Bus words per burst (1: single transfers).
    pub burst: u32,
}

/// What a bus moved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BusTraffic {
    /// Reads issued.
    pub reads: u64,
    /// Bits the reads asked for.
    pub bits: u64,
    /// Bus words transferred (whole bursts).
    pub words: u64,
    /// Bursts.
    pub bursts: u64,
}

impl BusTraffic {
    /// Bytes transferred.
    pub fn bytes(&self, bus: &Bus) -> u64 {
        self.words * u64::from(bus.width) / 8
    }
}

impl Bus {
    /// The traffic of `trace` with no cache: each read fetches every burst its bits overlap.
    pub fn traffic(&self, trace: &[Access]) -> BusTraffic {
        let burst_bytes = u64::from(self.width / 8) * u64::from(self.burst.max(1));
        let mut t = BusTraffic::default();
        for a in trace {
            let (first, last) = byte_range(a);
            let bursts = last / burst_bytes - first / burst_bytes + 1;
            t.reads += 1;
            t.bits += u64::from(a.bits);
            t.bursts += bursts;
            t.words += bursts * u64::from(self.burst.max(1));
        }
        t
    }
}

/// A set-associative cache with LRU replacement.
#[derive(Debug, Clone)]
pub struct Cache {
    line: u64,
    sets: u64,
    ways: usize,
    /// Per set, the resident line tags, most recently used first.
    tags: Vec<Vec<u64>>,
    /// Line accesses that hit.
    pub hits: u64,
    /// Line accesses that missed (each fetches one line).
    pub misses: u64,
}

impl Cache {
    /// `size` bytes of `line`-byte lines in `ways` ways (`size / (line ways)` sets, at least
    /// one). Refuses a line of 0 bytes, 0 ways, or a size below one set.
    pub fn new(size: u64, line: u64, ways: usize) -> Result<Cache, String> {
        if line == 0 || ways == 0 {
            return Err("cache: line and ways must be at least 1".into());
        }
        let sets = size / (line * ways as u64);
        if sets == 0 {
            return Err(format!(
                "cache: {size} bytes hold no set of {ways} lines of {line} bytes"
            ));
        }
        Ok(Cache {
            line,
            sets,
            ways,
            tags: vec![Vec::with_capacity(ways); sets as usize],
            hits: 0,
            misses: 0,
        })
    }

    /// Touches the line holding byte address `addr`.
    fn touch_line(&mut self, line_no: u64) {
        let set = (line_no % self.sets) as usize;
        let tags = &mut self.tags[set];
        if let Some(i) = tags.iter().position(|&t| t == line_no) {
            let t = tags.remove(i);
            tags.insert(0, t);
            self.hits += 1;
        } else {
            if tags.len() == self.ways {
                tags.pop();
            }
            tags.insert(0, line_no);
            self.misses += 1;
        }
    }

    /// Runs one access: every line its bytes overlap.
    pub fn access(&mut self, a: &Access) {
        let (first, last) = byte_range(a);
        for l in first / self.line..=last / self.line {
            self.touch_line(l);
        }
    }

    /// Line accesses (hits + misses).
    pub fn lookups(&self) -> u64 {
        self.hits + self.misses
    }

    /// Hits over line accesses (1 for none).
    pub fn hit_rate(&self) -> f64 {
        if self.lookups() == 0 {
            1.0
        } else {
            self.hits as f64 / self.lookups() as f64
        }
    }

    /// Bytes fetched from memory: one line per miss.
    pub fn bytes_fetched(&self) -> u64 {
        self.misses * self.line
    }

    /// Line size in bytes.
    pub fn line(&self) -> u64 {
        self.line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn acc(offset: u64, bits: u32) -> Access {
        Access {
            region: 0,
            offset,
            bits,
        }
    }

    #[test]
    fn bus_counts_the_bursts_a_read_overlaps() {
        let bus32 = Bus {
            width: 32,
            burst: 1,
        };
        // A 32-bit entry aligned: one word; straddling two words: two.
        assert_eq!(bus32.traffic(&[acc(0, 32)]).words, 1);
        assert_eq!(bus32.traffic(&[acc(16, 32)]).words, 2);
        // 14-bit field inside a word, and across the boundary.
        assert_eq!(bus32.traffic(&[acc(10, 14)]).words, 1);
        assert_eq!(bus32.traffic(&[acc(25, 14)]).words, 2);
        let bus64x4 = Bus {
            width: 64,
            burst: 4,
        };
        // 32-byte bursts: a read inside one burst moves 4 words of 8 bytes.
        let t = bus64x4.traffic(&[acc(0, 32), acc(255 * 8, 16)]);
        assert_eq!((t.bursts, t.words, t.bytes(&bus64x4)), (3, 12, 96));
        assert_eq!((t.reads, t.bits), (2, 48));
    }

    #[test]
    fn regions_never_share_a_line() {
        let mut c = Cache::new(1024, 64, 2).unwrap();
        c.access(&Access {
            region: 0,
            offset: 0,
            bits: 8,
        });
        c.access(&Access {
            region: 1,
            offset: 0,
            bits: 8,
        });
        assert_eq!((c.hits, c.misses), (0, 2));
    }

    #[test]
    fn lru_against_a_reference_model() {
        // A direct model: per set, the list of lines in use order, scanned linearly.
        let (size, line, ways) = (512u64, 16u64, 4usize);
        let sets = size / (line * ways as u64);
        let mut c = Cache::new(size, line, ways).unwrap();
        let mut model: Vec<Vec<u64>> = vec![Vec::new(); sets as usize];
        let (mut mh, mut mm) = (0u64, 0u64);
        let mut s = 12345u64;
        for _ in 0..20_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Mostly near addresses, some far.
            let addr = if s >> 60 == 0 {
                (s >> 20) % 100_000
            } else {
                (s >> 30) % 2048
            };
            let bits = 1 + (s >> 8) as u32 % 40;
            c.access(&acc(addr * 8, bits));
            let (first, last) = (addr, (addr * 8 + u64::from(bits) - 1) / 8);
            for l in first / line..=last / line {
                let set = &mut model[(l % sets) as usize];
                match set.iter().position(|&t| t == l) {
                    Some(i) => {
                        mh += 1;
                        set.remove(i);
                    }
                    None => {
                        mm += 1;
                        if set.len() == ways {
                            set.remove(ways - 1);
                        }
                    }
                }
                set.insert(0, l);
            }
        }
        assert_eq!((c.hits, c.misses), (mh, mm));
        assert!(c.hits > 0 && c.misses > 0);
        assert_eq!(c.bytes_fetched(), mm * line);
    }

    #[test]
    fn a_working_set_that_fits_hits_after_the_first_pass() {
        let mut c = Cache::new(4096, 32, 4).unwrap();
        for pass in 0..3 {
            for i in 0..100u64 {
                c.access(&acc(i * 32 * 8, 32));
            }
            if pass == 0 {
                assert_eq!(c.misses, 100);
            }
        }
        assert_eq!((c.hits, c.misses), (200, 100));
        assert!(Cache::new(16, 32, 1).is_err());
        assert!(Cache::new(1024, 0, 1).is_err());
    }
}
