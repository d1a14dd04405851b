//! Base colour textures, decoded to linear RGB, and their average over a UV triangle: the
//! diffuse reflectance of a radiosity element is the material factor times this average.

/// How texture coordinates outside [0, 1] are mapped (glTF sampler wrapS / wrapT).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WrapMode {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// A decoded texture: linear RGB texels, row-major from the top-left (glTF's UV origin).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
    pub wrap_s: WrapMode,
    pub wrap_t: WrapMode,
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1), 8-bit input.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The most samples per triangle side: bounds the cost of one average to 64² texel fetches.
const MAX_SAMPLES_PER_SIDE: usize = 64;

impl Texture {
    /// Builds a texture from 8-bit sRGB-encoded RGB(A) rows (alpha ignored).
    pub fn from_srgb8(width: u32, height: u32, channels: usize, data: &[u8]) -> Option<Self> {
        let n = (width as usize).checked_mul(height as usize)?;
        if channels == 0 || n == 0 || data.len() < n.checked_mul(channels)? {
            return None;
        }
        let lut: Vec<f32> = (0..=255u8)
            .map(|v| srgb_to_linear(f32::from(v) / 255.0))
            .collect();
        let texels = data
            .chunks_exact(channels)
            .take(n)
            .map(|p| {
                let g = |c: usize| lut[usize::from(p[c.min(channels - 1).min(2)])];
                if channels < 3 {
                    [g(0); 3]
                } else {
                    [g(0), g(1), g(2)]
                }
            })
            .collect();
        Some(Self {
            width,
            height,
            texels,
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
        })
    }

    fn wrap(i: i64, n: u32, mode: WrapMode) -> usize {
        let n = i64::from(n);
        let j = match mode {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::ClampToEdge => i.clamp(0, n - 1),
            WrapMode::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
        };
        j as usize
    }

    /// Bilinear sample at a UV (texel centres at half-integers, as in GPU sampling).
    pub fn sample(&self, uv: [f32; 2]) -> [f32; 3] {
        let x = f64::from(uv[0]) * f64::from(self.width) - 0.5;
        let y = f64::from(uv[1]) * f64::from(self.height) - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return [0.0; 3];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        // Coordinates are clamped to a range that wraps the same way, so the casts cannot overflow.
        let clampi = |v: f64| v.clamp(-1e15, 1e15) as i64;
        let (x0, y0) = (clampi(x0), clampi(y0));
        let at = |xi: i64, yi: i64| {
            let xs = Self::wrap(xi, self.width, self.wrap_s);
            let ys = Self::wrap(yi, self.height, self.wrap_t);
            self.texels[ys * self.width as usize + xs]
        };
        let (a, b, c, d) = (
            at(x0, y0),
            at(x0 + 1, y0),
            at(x0, y0 + 1),
            at(x0 + 1, y0 + 1),
        );
        [0, 1, 2].map(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }

    /// The average colour over a UV triangle: bilinear samples at the centroids of the `n²`
    /// equal-area subtriangles of a regular `n`-split, `n` growing with the triangle's texel
    /// footprint (about two samples per covered texel) up to 64. Deterministic.
    pub fn average_over_triangle(&self, uv: [[f32; 2]; 3]) -> [f32; 3] {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let e1 = [
            f64::from(uv[1][0] - uv[0][0]) * w,
            f64::from(uv[1][1] - uv[0][1]) * h,
        ];
        let e2 = [
            f64::from(uv[2][0] - uv[0][0]) * w,
            f64::from(uv[2][1] - uv[0][1]) * h,
        ];
        let texel_area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]).abs();
        let n = if texel_area.is_finite() {
            ((2.0 * texel_area).sqrt().ceil() as usize).clamp(1, MAX_SAMPLES_PER_SIDE)
        } else {
            1
        };
        let point = |a: f64, b: f64| -> [f32; 2] {
            // Barycentric (1 - a - b, a, b).
            [0, 1].map(|k| {
                let p0 = f64::from(uv[0][k]);
                (p0 + a * f64::from(uv[1][k] - uv[0][k]) + b * f64::from(uv[2][k] - uv[0][k]))
                    as f32
            })
        };
        let mut sum = [0f64; 3];
        let nf = n as f64;
        for i in 0..n {
            for j in 0..n - i {
                let mut add = |a: f64, b: f64| {
                    let s = self.sample(point(a / nf, b / nf));
                    for k in 0..3 {
                        sum[k] += f64::from(s[k]);
                    }
                };
                add(i as f64 + 1.0 / 3.0, j as f64 + 1.0 / 3.0);
                if i + j + 1 < n {
                    add(i as f64 + 2.0 / 3.0, j as f64 + 2.0 / 3.0);
                }
            }
        }
        let count = (n * n) as f64;
        sum.map(|s| (s / count) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // Left column white, right column black, 2 × 2.
        Texture::from_srgb8(2, 2, 3, &[255, 255, 255, 0, 0, 0, 255, 255, 255, 0, 0, 0]).unwrap()
    }

    #[test]
    fn srgb_endpoints_and_midpoint() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }

    #[test]
    fn average_over_the_whole_square_is_half() {
        let t = checker();
        let lower = t.average_over_triangle([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        let upper = t.average_over_triangle([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        // Bilinear filtering with repeat wrap blurs the columns but keeps the mean.
        let mean = (lower[0] + upper[0]) / 2.0;
        assert!((mean - 0.5).abs() < 0.02, "{lower:?} {upper:?}");
    }

    #[test]
    fn a_triangle_inside_one_column_takes_its_colour() {
        let mut t = checker();
        t.wrap_s = WrapMode::ClampToEdge;
        let a = t.average_over_triangle([[0.0, 0.0], [0.2, 0.0], [0.0, 1.0]]);
        assert!(a[1] > 0.95, "{a:?}");
        let b = t.average_over_triangle([[1.0, 0.0], [0.8, 0.0], [1.0, 1.0]]);
        assert!(b[1] < 0.05, "{b:?}");
    }

    #[test]
    fn rejects_short_data() {
        assert!(Texture::from_srgb8(4, 4, 3, &[0; 10]).is_none());
        assert!(Texture::from_srgb8(0, 4, 3, &[]).is_none());
    }
}
