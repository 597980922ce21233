//! Reading and writing NumPy `.npy` files (format versions 1.0, 2.0 and 3.0), the array
//! format plugins exchange with cgnodes. The format is a magic string, a version, a header
//! length, a Python-literal header `{'descr': '<f8', 'fortran_order': False, 'shape': (N, 3), }`
//! padded to a multiple of 64 bytes, then the raw array data
//! (<https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html>).

use std::path::Path;

const MAGIC: &[u8] = b"\x93NUMPY";

/// Why an `.npy` file could not be read, written or converted; the file's path is added by
/// [`NpyArray::read`] and [`NpyArray::write`].
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// A big-endian element type (NumPy's `>`), which cgnodes does not swap.
    #[error("dtype '{descr}' is big-endian; write little-endian arrays (arr.astype('<{code}'))")]
    BigEndian {
        /// The header's `descr`.
        descr: String,
        /// Its type code without the byte order.
        code: String,
    },
    /// A byte-order character other than `<`, `|` or `=`.
    #[error("unsupported dtype '{0}'")]
    ByteOrder(String),
    /// A type code cgnodes does not read.
    #[error("unsupported dtype '{0}' (cgnodes reads f8, f4, i8, i4, u8, u4, u1 and b1)")]
    DType(String),
    /// A `u8` element above `i64::MAX`, as an index.
    #[error("index out of range")]
    IndexOutOfRange,
    /// Integers were asked of a floating-point array.
    #[error("expected an integer array, got dtype {}", .0.descr())]
    NotInteger(DType),
    /// The bytes do not start with the `.npy` magic string.
    #[error("not an .npy file (no \\x93NUMPY magic)")]
    NoMagic,
    /// A format version other than 1, 2 or 3.
    #[error("unsupported .npy format version {0}")]
    Version(u8),
    /// The file ends inside its header.
    #[error("truncated .npy header")]
    TruncatedHeader,
    /// The header is not UTF-8.
    #[error("the .npy header is not text")]
    HeaderNotText,
    /// The header lacks one of `descr`, `fortran_order`, `shape`.
    #[error("the .npy header has no '{0}'")]
    MissingField(&'static str),
    /// The header's `shape` is not a tuple of whole numbers.
    #[error("bad shape {0}")]
    BadShape(String),
    /// A dimension larger than the file (issue 23).
    #[error("shape {} declares a dimension of {dim}, more than a {file_len}-byte file can hold", shape_str(.shape))]
    DimensionTooLarge {
        /// The declared shape.
        shape: Vec<usize>,
        /// The offending dimension.
        dim: usize,
        /// The file's size in bytes.
        file_len: usize,
    },
    /// A shape whose element or byte count overflows.
    #[error("shape {} is too large", shape_str(.0))]
    TooLarge(Vec<usize>),
    /// The data is shorter or longer than the shape and type need.
    #[error("the .npy data is {}: shape {} of {} needs {want} bytes, found {found}", if .found < .want { "truncated" } else { "longer than its shape" }, shape_str(.shape), .dtype.descr())]
    DataSize {
        /// The declared shape.
        shape: Vec<usize>,
        /// The declared element type.
        dtype: DType,
        /// Bytes the shape needs.
        want: usize,
        /// Bytes present.
        found: usize,
    },
    /// The file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The file was read but its contents are not a valid array.
    #[error("{}: {source}", .path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with its contents.
        source: Box<NpyError>,
    },
}

/// The element types cgnodes reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DType {
    /// `<f8`
    F64,
    /// `<f4`
    F32,
    /// `<i8`
    I64,
    /// `<i4`
    I32,
    /// `<u8`
    U64,
    /// `<u4`
    U32,
    /// `|u1`
    U8,
    /// `|b1`
    Bool,
}

impl DType {
    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            DType::F64 | DType::I64 | DType::U64 => 8,
            DType::F32 | DType::I32 | DType::U32 => 4,
            DType::U8 | DType::Bool => 1,
        }
    }

    /// The `descr` string NumPy writes for this type.
    pub fn descr(self) -> &'static str {
        match self {
            DType::F64 => "<f8",
            DType::F32 => "<f4",
            DType::I64 => "<i8",
            DType::I32 => "<i4",
            DType::U64 => "<u8",
            DType::U32 => "<u4",
            DType::U8 => "|u1",
            DType::Bool => "|b1",
        }
    }

    fn parse(descr: &str) -> Result<DType, NpyError> {
        // Split after the first character, not the first byte: a multi-byte first character
        // made `split_at(1)` panic (issue 23).
        let cut = descr.chars().next().map_or(0, char::len_utf8);
        let (order, code) = descr.split_at(cut);
        if order == ">" && !matches!(code, "u1" | "b1" | "i1") {
            return Err(NpyError::BigEndian {
                descr: descr.into(),
                code: code.into(),
            });
        }
        if !matches!(order, "<" | "|" | "=") {
            return Err(NpyError::ByteOrder(descr.into()));
        }
        Ok(match code {
            "f8" => DType::F64,
            "f4" => DType::F32,
            "i8" => DType::I64,
            "i4" => DType::I32,
            "u8" => DType::U64,
            "u4" => DType::U32,
            "u1" => DType::U8,
            "b1" => DType::Bool,
            _ => return Err(NpyError::DType(descr.into())),
        })
    }
}

/// An n-dimensional array read from an `.npy` file: shape, element type and the data in
/// C order (little-endian bytes).
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// Dimensions, outermost first.
    pub shape: Vec<usize>,
    /// Element type.
    pub dtype: DType,
    data: Vec<u8>,
}

impl NpyArray {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the array has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The shape as NumPy prints it, for messages: `(100, 3)`.
    pub fn shape_str(&self) -> String {
        shape_str(&self.shape)
    }

    fn elem(&self, i: usize) -> &[u8] {
        let s = self.dtype.size();
        &self.data[i * s..(i + 1) * s]
    }

    /// The elements as `f64` (any numeric type converts).
    pub fn to_f64(&self) -> Vec<f64> {
        (0..self.len())
            .map(|i| {
                let b = self.elem(i);
                match self.dtype {
                    DType::F64 => f64::from_le_bytes(b.try_into().unwrap_or([0; 8])),
                    DType::F32 => f32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
                    DType::I64 => i64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f64,
                    DType::I32 => i32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
                    DType::U64 => u64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f64,
                    DType::U32 => u32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64,
                    DType::U8 | DType::Bool => b[0] as f64,
                }
            })
            .collect()
    }

    /// The elements as `f32` (any numeric type converts).
    pub fn to_f32(&self) -> Vec<f32> {
        if self.dtype == DType::F32 {
            return self
                .data
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
        }
        self.to_f64().into_iter().map(|x| x as f32).collect()
    }

    /// The elements as integers; fails for floating-point arrays (indices must be integers).
    pub fn to_i64(&self) -> Result<Vec<i64>, NpyError> {
        let conv = |b: &[u8]| -> Result<i64, NpyError> {
            Ok(match self.dtype {
                DType::I64 => i64::from_le_bytes(b.try_into().unwrap_or([0; 8])),
                DType::I32 => i32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as i64,
                DType::U64 => i64::try_from(u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
                    .map_err(|_| NpyError::IndexOutOfRange)?,
                DType::U32 => u32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as i64,
                DType::U8 | DType::Bool => b[0] as i64,
                DType::F64 | DType::F32 => return Err(NpyError::NotInteger(self.dtype)),
            })
        };
        (0..self.len()).map(|i| conv(self.elem(i))).collect()
    }

    /// An array of `shape` and `dtype` from the little-endian bytes of its C-order values.
    fn pack<const N: usize>(
        shape: &[usize],
        dtype: DType,
        values: impl ExactSizeIterator<Item = [u8; N]>,
    ) -> NpyArray {
        let mut data = Vec::with_capacity(values.len() * N);
        for b in values {
            data.extend_from_slice(&b);
        }
        NpyArray {
            shape: shape.to_vec(),
            dtype,
            data,
        }
    }

    /// An `f64` array of `shape` from C-order values.
    pub fn from_f64(shape: &[usize], values: &[f64]) -> NpyArray {
        NpyArray::pack(shape, DType::F64, values.iter().map(|v| v.to_le_bytes()))
    }

    /// An `f32` array of `shape` from C-order values.
    pub fn from_f32(shape: &[usize], values: &[f32]) -> NpyArray {
        NpyArray::pack(shape, DType::F32, values.iter().map(|v| v.to_le_bytes()))
    }

    /// An `int32` array of `shape` from C-order values (mesh indices; NumPy indexes with it
    /// directly).
    pub fn from_i32(shape: &[usize], values: &[i32]) -> NpyArray {
        NpyArray::pack(shape, DType::I32, values.iter().map(|v| v.to_le_bytes()))
    }

    /// The file bytes (format version 1.0, header padded to 64 bytes as NumPy does).
    pub fn to_bytes(&self) -> Vec<u8> {
        let shape = match self.shape.len() {
            1 => format!("({},)", self.shape[0]),
            _ => shape_str(&self.shape),
        };
        let mut header = format!(
            "{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}",
            self.dtype.descr()
        );
        // magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
        let unpadded = 10 + header.len() + 1;
        header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
        header.push('\n');
        let mut out = Vec::with_capacity(10 + header.len() + self.data.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(&self.data);
        out
    }

    /// Parses `.npy` file bytes. Fortran-ordered arrays are converted to C order.
    pub fn from_bytes(bytes: &[u8]) -> Result<NpyArray, NpyError> {
        if bytes.len() < 10 || &bytes[..6] != MAGIC {
            return Err(NpyError::NoMagic);
        }
        let (hlen, start) = match bytes[6] {
            1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
            2 | 3 if bytes.len() >= 12 => (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            ),
            v => return Err(NpyError::Version(v)),
        };
        let header = bytes
            .get(start..start + hlen)
            .ok_or(NpyError::TruncatedHeader)?;
        let header = std::str::from_utf8(header).map_err(|_| NpyError::HeaderNotText)?;
        let descr = header_field(header, "descr")
            .ok_or(NpyError::MissingField("descr"))?
            .trim_matches(|c| c == '\'' || c == '"')
            .to_string();
        let dtype = DType::parse(&descr)?;
        let fortran = header_field(header, "fortran_order")
            .ok_or(NpyError::MissingField("fortran_order"))?
            == "True";
        let shape_text = header_field(header, "shape").ok_or(NpyError::MissingField("shape"))?;
        let shape: Vec<usize> = shape_text
            .trim_matches(|c| c == '(' || c == ')')
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().map_err(|_| NpyError::BadShape(shape_text.into())))
            .collect::<Result<_, _>>()?;
        // No dimension may exceed what the file could hold (issue 23): with another
        // dimension 0 the data check below passes, and readers size buffers from the rest
        // (a `(10**18, 0)` array of triangles asked for 10^18 face counts).
        if let Some(&d) = shape.iter().find(|&&d| d > bytes.len()) {
            return Err(NpyError::DimensionTooLarge {
                dim: d,
                file_len: bytes.len(),
                shape,
            });
        }
        let n: usize = shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .ok_or_else(|| NpyError::TooLarge(shape.clone()))?;
        let data = &bytes[start + hlen..];
        let want = n
            .checked_mul(dtype.size())
            .ok_or_else(|| NpyError::TooLarge(shape.clone()))?;
        if data.len() != want {
            return Err(NpyError::DataSize {
                shape,
                dtype,
                want,
                found: data.len(),
            });
        }
        let mut a = NpyArray {
            shape,
            dtype,
            data: data.to_vec(),
        };
        if fortran && a.shape.len() > 1 {
            a.data = fortran_to_c(&a.data, &a.shape, dtype.size());
        }
        Ok(a)
    }

    /// Reads an `.npy` file.
    pub fn read(path: &Path) -> Result<NpyArray, NpyError> {
        let bytes = std::fs::read(path).map_err(|source| NpyError::Io {
            path: path.into(),
            source,
        })?;
        NpyArray::from_bytes(&bytes).map_err(|e| NpyError::File {
            path: path.into(),
            source: Box::new(e),
        })
    }

    /// Writes an `.npy` file.
    pub fn write(&self, path: &Path) -> Result<(), NpyError> {
        std::fs::write(path, self.to_bytes()).map_err(|source| NpyError::Io {
            path: path.into(),
            source,
        })
    }
}

/// `(a, b, c)` as NumPy prints a shape.
pub fn shape_str(shape: &[usize]) -> String {
    match shape.len() {
        1 => format!("({},)", shape[0]),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The text of `key`'s value in a header dict (a quoted string, a word or a tuple).
fn header_field<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let pats = [format!("'{key}'"), format!("\"{key}\"")];
    let i = pats
        .iter()
        .find_map(|p| header.find(p.as_str()).map(|i| i + p.len()))?;
    let rest = header[i..].trim_start().strip_prefix(':')?.trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')')? + 1
    } else if let Some(q) = rest.chars().next().filter(|c| *c == '\'' || *c == '"') {
        rest[1..].find(q)? + 2
    } else {
        rest.find([',', '}'])?
    };
    Some(rest[..end].trim())
}

/// Reorders Fortran-order (column-major) element bytes to C order.
fn fortran_to_c(data: &[u8], shape: &[usize], size: usize) -> Vec<u8> {
    let n: usize = shape.iter().product();
    if n == 0 {
        // Nothing to reorder; the strides of the other dimensions could overflow.
        return Vec::new();
    }
    // Fortran strides (in elements): first axis fastest.
    let mut fstride = vec![1usize; shape.len()];
    for k in 1..shape.len() {
        fstride[k] = fstride[k - 1] * shape[k - 1];
    }
    let mut out = Vec::with_capacity(data.len());
    let mut idx = vec![0usize; shape.len()];
    for _ in 0..n {
        let off: usize = idx.iter().zip(&fstride).map(|(i, s)| i * s).sum();
        out.extend_from_slice(&data[off * size..(off + 1) * size]);
        // Advance the C-order multi-index (last axis fastest).
        for k in (0..shape.len()).rev() {
            idx[k] += 1;
            if idx[k] < shape[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_alignment() {
        let a = NpyArray::from_f64(&[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5]);
        let b = a.to_bytes();
        // NumPy aligns the data to 64 bytes.
        assert_eq!((b.len() - 48) % 64, 0);
        assert_eq!(b[b.len() - 49], b'\n');
        let back = NpyArray::from_bytes(&b).unwrap();
        assert_eq!(back, a);
        assert_eq!(back.to_f64(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.5]);
        assert!(back.to_i64().is_err());
        let one = NpyArray::from_i32(&[3], &[7, -1, 2]);
        let back = NpyArray::from_bytes(&one.to_bytes()).unwrap();
        assert_eq!(back.shape, vec![3]);
        assert_eq!(back.to_i64().unwrap(), vec![7, -1, 2]);
    }

    #[test]
    fn reads_a_file_numpy_wrote() {
        // Bytes of `np.save(f, np.arange(6, dtype='<i8').reshape(2, 3).T)`: a Fortran-order
        // (3, 2) array, header written by NumPy 1.x (16-byte alignment, version 1.0).
        let header = "{'descr': '<i8', 'fortran_order': True, 'shape': (3, 2), }";
        let mut h = header.to_string();
        while !(10 + h.len() + 1).is_multiple_of(16) {
            h.push(' ');
        }
        h.push('\n');
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(h.len() as u16).to_le_bytes());
        b.extend_from_slice(h.as_bytes());
        for v in 0i64..6 {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let a = NpyArray::from_bytes(&b).unwrap();
        assert_eq!(a.shape, vec![3, 2]);
        // Transpose of [[0,1,2],[3,4,5]] in C order.
        assert_eq!(a.to_i64().unwrap(), vec![0, 3, 1, 4, 2, 5]);
    }

    #[test]
    fn refuses_bad_files() {
        assert!(NpyArray::from_bytes(b"hello").is_err());
        let mut b = NpyArray::from_f64(&[4, 3], &[0.0; 12]).to_bytes();
        b.truncate(b.len() - 8);
        assert!(NpyArray::from_bytes(&b)
            .unwrap_err()
            .to_string()
            .contains("truncated"));
        let big = b"\x93NUMPY\x01\x00\x3c\x00{'descr': '>f8', 'fortran_order': False, 'shape': (1,), }    \n";
        assert!(NpyArray::from_bytes(big)
            .unwrap_err()
            .to_string()
            .contains("big-endian"));
    }

    /// An `.npy` file with `header` (a dict literal) and `data` after it.
    fn npy(header: &str, data: &[u8]) -> Vec<u8> {
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(data);
        b
    }

    /// Issue 23: hostile headers are errors, not panics or huge allocations: a multi-byte
    /// first character in 'descr' (a panic in `split_at`), a shape whose product overflows,
    /// a zero-size shape with a huge other dimension (Fortran strides overflowed, and decoders
    /// sized buffers from it), and data longer than the shape (it was silently cut).
    #[test]
    fn hostile_headers_are_errors() {
        let h = "{'descr': '\u{e9}8', 'fortran_order': False, 'shape': (1,), }";
        let e = NpyArray::from_bytes(&npy(h, &[0; 8]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unsupported dtype"), "{e}");
        let h = "{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 2), }";
        let e = NpyArray::from_bytes(&npy(h, &[])).unwrap_err().to_string();
        assert!(e.contains("declares a dimension of 4294967296"), "{e}");
        let h = "{'descr': '<f8', 'fortran_order': True, 'shape': (100000000000000, 100000000000000, 0), }";
        let e = NpyArray::from_bytes(&npy(h, &[])).unwrap_err().to_string();
        assert!(e.contains("declares a dimension of 100000000000000"), "{e}");
        let h = "{'descr': '<f8', 'fortran_order': True, 'shape': (3, 0), }";
        assert!(NpyArray::from_bytes(&npy(h, &[])).unwrap().is_empty());
        let h = "{'descr': '<i4', 'fortran_order': False, 'shape': (2,), }";
        let e = NpyArray::from_bytes(&npy(h, &[0; 12]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("longer than its shape: shape (2,) of <i4 needs 8 bytes, found 12"),
            "{e}"
        );
        assert_eq!(NpyArray::from_bytes(&npy(h, &[0; 8])).unwrap().len(), 2);
    }
}
