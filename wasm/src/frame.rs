//! The frames of the interface (see the crate documentation): what a request holds is read
//! with [`Reader`], which runs out with an error instead of reading past the frame, and results
//! are built with [`Writer`].

/// Reads the items of a request frame in order.
pub struct Reader<'a> {
    words: &'a [u32],
    at: usize,
}

impl<'a> Reader<'a> {
    pub fn new(words: &'a [u32]) -> Self {
        Self { words, at: 0 }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u32], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.words.len())
            .ok_or_else(|| {
                format!(
                    "the request ends at word {} but an item needs {n} more words from word {}",
                    self.words.len(),
                    self.at
                )
            })?;
        let out = &self.words[self.at..end];
        self.at = end;
        Ok(out)
    }

    pub fn u32(&mut self) -> Result<u32, String> {
        Ok(self.take(1)?[0])
    }

    /// An `f32` item's bits.
    pub fn f32_bits(&mut self) -> Result<u32, String> {
        self.u32()
    }

    /// Words read so far.
    pub fn position(&self) -> usize {
        self.at
    }

    pub fn u64(&mut self) -> Result<u64, String> {
        let w = self.take(2)?;
        Ok(u64::from(w[0]) | (u64::from(w[1]) << 32))
    }

    pub fn words(&mut self) -> Result<Vec<u32>, String> {
        let n = self.u32()? as usize;
        Ok(self.take(n)?.to_vec())
    }

    pub fn floats(&mut self) -> Result<Vec<f32>, String> {
        Ok(self.words()?.into_iter().map(f32::from_bits).collect())
    }

    pub fn bytes(&mut self) -> Result<Vec<u8>, String> {
        let n = self.u32()? as usize;
        let words = self.take(n.div_ceil(4))?;
        let mut out: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        out.truncate(n);
        Ok(out)
    }

    pub fn string(&mut self) -> Result<String, String> {
        String::from_utf8(self.bytes()?).map_err(|_| "a name is not valid UTF-8".to_string())
    }
}

/// Builds a result frame.
#[derive(Default)]
pub struct Writer(Vec<u32>);

impl Writer {
    pub fn u32(&mut self, v: u32) {
        self.0.push(v);
    }

    pub fn f32(&mut self, v: f32) {
        self.0.push(v.to_bits());
    }

    pub fn u64(&mut self, v: u64) {
        self.0.push(v as u32);
        self.0.push((v >> 32) as u32);
    }

    pub fn words(&mut self, a: &[u32]) {
        self.0.push(a.len() as u32);
        self.0.extend_from_slice(a);
    }

    pub fn floats(&mut self, a: &[f32]) {
        self.0.push(a.len() as u32);
        self.0.extend(a.iter().map(|x| x.to_bits()));
    }

    pub fn bytes(&mut self, b: &[u8]) {
        self.0.push(b.len() as u32);
        self.0.extend(b.chunks(4).map(|c| {
            let mut w = [0u8; 4];
            w[..c.len()].copy_from_slice(c);
            u32::from_le_bytes(w)
        }));
    }

    pub fn string(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }

    pub fn finish(self) -> Vec<u32> {
        self.0
    }
}
