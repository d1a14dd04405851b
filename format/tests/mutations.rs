//! A stable, deterministic stand-in for the cargo-fuzz target (`fuzz/`): thousands of inputs
//! mutated from valid files by a seeded PRNG go through `read` and `validate_bytes`. Half of
//! them get their checksums recomputed so that the damage reaches the content checks. A
//! counting allocator asserts that no input makes the library allocate more than a small
//! multiple of its size. Crash inputs found by cargo-fuzz live in `tests/regressions/` and are
//! replayed here too.
//!
//! The allocator counts per thread: the test harness runs tests on parallel threads, and a
//! shared counter would charge one test's allocations to another's input.

mod common;

use hce_format::{example, read, validate_bytes, write};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    // Bytes this thread holds and the most it held since `check` last reset it. Signed and
    // wrapping: a thread may free memory another thread allocated. `const` initialisers need
    // no allocation and no destructor, so the allocator may touch them.
    static CURRENT: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn size(layout: Layout) -> isize {
    layout.size() as isize
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // `try_with`: a thread being torn down has no counters left, and is no test's input.
        let _ = CURRENT.try_with(|c| {
            let now = c.get().wrapping_add(size(layout));
            c.set(now);
            let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
        });
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        let _ = CURRENT.try_with(|c| c.set(c.get().wrapping_sub(size(layout))));
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// xorshift64*: small, seeded, the same on every machine.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        match rng.below(6) {
            0 => {
                let at = rng.below(b.len());
                b[at] ^= 1 << rng.below(8);
            }
            1 => {
                let at = rng.below(b.len());
                b[at] = rng.next() as u8;
            }
            2 if b.len() >= 4 => {
                // A field-sized random value at a 4-aligned position (counts, offsets, indices).
                let at = rng.below(b.len() / 4) * 4;
                let v = match rng.below(4) {
                    0 => u32::MAX,
                    1 => rng.below(16) as u32,
                    2 => 0x8000_0000,
                    _ => rng.next() as u32,
                };
                b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            3 => b.truncate(rng.below(b.len() + 1)),
            4 => {
                let extra = rng.below(300);
                b.extend((0..extra).map(|_| rng.next() as u8));
            }
            _ => {
                // Copy a chunk of the file over another place.
                let n = rng.below(64);
                let from = rng.below(b.len().saturating_sub(n));
                let to = rng.below(b.len().saturating_sub(n));
                let chunk = b[from..(from + n).min(b.len())].to_vec();
                let end = (to + chunk.len()).min(b.len());
                b[to..end].copy_from_slice(&chunk[..end - to]);
            }
        }
        if b.is_empty() {
            break;
        }
    }
    if rng.below(2) == 0 {
        if b.len() >= 32 {
            // Keep file_length honest sometimes, so that damage gets past the length check.
            let len = b.len() as u64;
            if rng.below(2) == 0 {
                b[16..24].copy_from_slice(&len.to_le_bytes());
            }
        }
        common::reseal(&mut b);
    }
    b
}

/// Runs one input and checks the properties every input must have.
fn check(input: &[u8]) -> (bool, bool) {
    let base = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(base));
    let read_result = read(input);
    let problems = validate_bytes(input);
    let peak = PEAK.with(Cell::get).wrapping_sub(base);
    assert!(
        peak <= (64 * input.len() + (1 << 20)) as isize,
        "{} bytes of input made the library hold {peak} bytes",
        input.len()
    );
    if problems.is_empty() {
        assert!(read_result.is_ok(), "valid per validator but unreadable");
    }
    if let Ok(c) = &read_result {
        // Whatever was readable writes back to something that reads the same.
        let again = write(c).expect("a read container is writable");
        // Compared as bytes: NaN coordinates are legal to read and unequal to themselves.
        let reread = read(&again).expect("rewritten file reads");
        assert_eq!(write(&reread).unwrap(), again);
    }
    (read_result.is_ok(), problems.is_empty())
}

#[test]
fn seeded_mutations_never_panic_or_overallocate() {
    let seeds = [
        write(&example::single_triangle()).unwrap(),
        write(&example::two_triangles()).unwrap(),
        write(&example::grid(3, 3)).unwrap(),
    ];
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut readable, mut valid) = (0, 0);
    let iterations = 50_000;
    for i in 0..iterations {
        let input = mutate(&mut rng, &seeds[i % seeds.len()]);
        let (r, v) = check(&input);
        readable += usize::from(r);
        valid += usize::from(v);
    }
    println!("{iterations} mutated inputs: {readable} readable, {valid} valid");
    // The mix must reach past the checksums, or the test exercises nothing but the header.
    assert!(readable > iterations / 20, "only {readable} readable");
    assert!(valid < readable);
}

#[test]
fn regression_inputs_are_handled() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regressions");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).expect("tests/regressions exists") {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "md") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        check(&bytes);
        n += 1;
    }
    // An empty or misplaced directory must not pass for a replayed corpus.
    assert!(
        n > 0,
        "no regression inputs in {}: the crash inputs of cargo-fuzz belong there",
        dir.display()
    );
    println!("{n} regression inputs replayed from {}", dir.display());
}
