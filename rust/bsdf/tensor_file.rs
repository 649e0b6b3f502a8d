//! The `tensor_file` container, version 1.0 (Mitsuba's `TensorFile`, the format of the RGL
//! material database's `.bsdf` files): named, typed, shaped arrays.
//!
//! All integers are little-endian:
//!
//! ```text
//! 12 bytes   magic "tensor_file\0"
//!  2 bytes   version: major 1, minor 0
//!  u32       number of fields
//! per field: u16 name length, the name (UTF-8), u16 rank, u8 dtype code,
//!            u64 byte offset of the data in the file, rank × u64 shape
//! ```
//!
//! Each field's data is its elements in C order at its offset. The header is read and
//! checked first: every count, size and offset it states is checked, with checked
//! arithmetic, against the file's length and against [`MAX_BYTES`] before anything is
//! allocated for it. Only then are the bytes the fields declare read, so that any file
//! named `.bsdf` (a disk image, a sparse file of 20 GB) costs a few reads to refuse.

use std::fs::File;
use std::io::{BufReader, ErrorKind, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub const MAGIC: &[u8; 12] = b"tensor_file\0";
pub const VERSION: [u8; 2] = [1, 0];
/// Bytes before the first field's header: magic, version, field count.
pub const PREAMBLE_BYTES: usize = 12 + 2 + 4;
/// The most bytes a tensor file may declare, header and data: 256 MiB. The RGL database's
/// RGB files are about 1 MB and its spectral ones a few tens of MB; a header that declares
/// more is refused before anything is read, so a stray file never fills memory.
pub const MAX_BYTES: u64 = 256 << 20;
/// The most fields a tensor file may declare (the RGL files have about ten).
pub const MAX_FIELDS: u32 = 4096;

/// Element types, numbered as the format numbers them (0 is invalid).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dtype {
    UInt8 = 1,
    Int8,
    UInt16,
    Int16,
    UInt32,
    Int32,
    UInt64,
    Int64,
    Float16,
    Float32,
    Float64,
}

impl Dtype {
    const ALL: [Dtype; 11] = [
        Dtype::UInt8,
        Dtype::Int8,
        Dtype::UInt16,
        Dtype::Int16,
        Dtype::UInt32,
        Dtype::Int32,
        Dtype::UInt64,
        Dtype::Int64,
        Dtype::Float16,
        Dtype::Float32,
        Dtype::Float64,
    ];

    pub fn from_code(code: u8) -> Option<Dtype> {
        Dtype::ALL.into_iter().find(|&dtype| dtype as u8 == code)
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            Dtype::UInt8 | Dtype::Int8 => 1,
            Dtype::UInt16 | Dtype::Int16 | Dtype::Float16 => 2,
            Dtype::UInt32 | Dtype::Int32 | Dtype::Float32 => 4,
            Dtype::UInt64 | Dtype::Int64 | Dtype::Float64 => 8,
        }
    }

    /// numpy's name for the type.
    pub fn name(self) -> &'static str {
        match self {
            Dtype::UInt8 => "uint8",
            Dtype::Int8 => "int8",
            Dtype::UInt16 => "uint16",
            Dtype::Int16 => "int16",
            Dtype::UInt32 => "uint32",
            Dtype::Int32 => "int32",
            Dtype::UInt64 => "uint64",
            Dtype::Int64 => "int64",
            Dtype::Float16 => "float16",
            Dtype::Float32 => "float32",
            Dtype::Float64 => "float64",
        }
    }
}

/// One named array of a tensor file: where its data lie and how to read them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    pub dtype: Dtype,
    pub shape: Vec<usize>,
    /// Byte offset of the data in the file.
    pub offset: usize,
    /// Byte length of the data: the product of the shape times the element size.
    pub byte_len: usize,
}

impl Field {
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A parsed tensor file: its bytes and the fields that index into them.
#[derive(Clone, Debug)]
pub struct TensorFile {
    path: PathBuf,
    bytes: Vec<u8>,
    fields: Vec<Field>,
}

impl TensorFile {
    /// Reads and parses the file at `path`: the header first, checked, then only the
    /// bytes its fields declare (at most [`MAX_BYTES`]).
    pub fn read(path: &Path) -> Result<TensorFile> {
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let metadata = file.metadata().map_err(|e| Error::io(path, e))?;
        if metadata.is_dir() {
            return Err(Error::io(path, std::io::Error::from(ErrorKind::IsADirectory)));
        }
        let mut reader = BufReader::new(file);
        let fields = parse_header(path, &mut reader, metadata.len())?;
        // Checked by parse_header: within the file and at most MAX_BYTES.
        let end = data_end(&fields);
        let mut file = reader.into_inner();
        file.seek(SeekFrom::Start(0)).map_err(|e| Error::io(path, e))?;
        let mut bytes = Vec::with_capacity(end);
        file.take(end as u64)
            .read_to_end(&mut bytes)
            .map_err(|e| Error::io(path, e))?;
        if bytes.len() < end {
            return Err(Error::bsdf_format(
                path,
                format!(
                    "truncated while being read: its fields end at byte {end}, but only {} bytes could be read",
                    bytes.len()
                ),
            ));
        }
        Ok(TensorFile {
            path: path.to_path_buf(),
            bytes,
            fields,
        })
    }

    /// Parses the bytes of a tensor file; `path` only names the file in errors.
    pub fn parse(path: &Path, bytes: Vec<u8>) -> Result<TensorFile> {
        let fields = parse_header(path, &mut bytes.as_slice(), bytes.len() as u64)?;
        Ok(TensorFile {
            path: path.to_path_buf(),
            bytes,
            fields,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The fields in the order the file lists them.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|field| field.name == name)
    }

    /// The raw (little-endian) bytes of a field's data.
    pub fn data(&self, field: &Field) -> &[u8] {
        &self.bytes[field.offset..field.offset + field.byte_len]
    }

    /// The field `name`, checked to exist and to have `dtype` and `rank` dimensions.
    pub fn require(&self, name: &str, dtype: Dtype, rank: usize) -> Result<&Field> {
        let field = self
            .field(name)
            .ok_or_else(|| self.error(format!("has no field `{name}`")))?;
        if field.dtype != dtype || field.shape.len() != rank {
            return Err(self.error(format!(
                "field `{name}` is {} with shape {:?}; expected {} with {rank} dimension{}",
                field.dtype.name(),
                field.shape,
                dtype.name(),
                if rank == 1 { "" } else { "s" }
            )));
        }
        Ok(field)
    }

    /// The values of a `float32` field of `rank` dimensions, with its shape.
    pub fn f32_values(&self, name: &str, rank: usize) -> Result<(Vec<usize>, Vec<f32>)> {
        let field = self.require(name, Dtype::Float32, rank)?;
        let values = self
            .data(field)
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok((field.shape.clone(), values))
    }

    /// A format error about this file.
    pub(crate) fn error(&self, message: impl Into<String>) -> Error {
        Error::bsdf_format(&self.path, message)
    }
}

/// The byte just past the last field's data (0 without fields).
fn data_end(fields: &[Field]) -> usize {
    fields
        .iter()
        .map(|field| field.offset + field.byte_len)
        .max()
        .unwrap_or(0)
}

/// Reads the header from `source`, a file of `len` bytes, checking every field against
/// the file's length and [`MAX_BYTES`].
fn parse_header(path: &Path, source: &mut impl Read, len: u64) -> Result<Vec<Field>> {
    let mut cursor = Cursor {
        path,
        source,
        len,
        at: 0,
    };
    let magic = cursor.take(MAGIC.len(), "the magic number")?;
    if magic != MAGIC {
        return Err(Error::bsdf_format(
            path,
            format!(
                "not a tensor file: starts with {:?}, expected {:?}",
                String::from_utf8_lossy(&magic),
                String::from_utf8_lossy(MAGIC)
            ),
        ));
    }
    let version = cursor.take(2, "the version")?;
    if version != VERSION {
        return Err(Error::bsdf_format(
            path,
            format!(
                "tensor file version {}.{} is not supported; expected {}.{}",
                version[0], version[1], VERSION[0], VERSION[1]
            ),
        ));
    }
    let n_fields = cursor.u32("the field count")?;
    if n_fields > MAX_FIELDS {
        return Err(Error::bsdf_format(
            path,
            format!("declares {n_fields} fields; a tensor file frenbrdf reads has at most {MAX_FIELDS}"),
        ));
    }

    // All headers first, so that a file cut short in its header says so; nothing is
    // allocated by the stated count, as each header is read before it is stored.
    let mut headers: Vec<(String, Dtype, u64, Vec<u64>)> = Vec::new();
    for index in 0..n_fields {
        let what = |part: &str| format!("{part} of field {index} (of {n_fields})");
        let name_len = cursor.u16(&what("the name length"))? as usize;
        let name = cursor.take(name_len, &what("the name"))?;
        let name = String::from_utf8(name).map_err(|e| {
            Error::bsdf_format(
                path,
                format!("the name of field {index} is not UTF-8: {:?}", e.as_bytes()),
            )
        })?;
        let rank = cursor.u16(&format!("the rank of field `{name}`"))? as usize;
        let code = cursor.u8(&format!("the dtype of field `{name}`"))?;
        let dtype = Dtype::from_code(code).ok_or_else(|| {
            Error::bsdf_format(
                path,
                format!("field `{name}` has unknown dtype code {code} (valid codes are 1 to 11)"),
            )
        })?;
        let offset = cursor.u64(&format!("the data offset of field `{name}`"))?;
        let shape_bytes = cursor.take(8 * rank, &format!("the {rank}-dimensional shape of field `{name}`"))?;
        let shape = shape_bytes
            .chunks_exact(8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8-byte chunks")))
            .collect();
        if headers.iter().any(|(other, ..)| *other == name) {
            return Err(Error::bsdf_format(path, format!("field `{name}` appears twice")));
        }
        headers.push((name, dtype, offset, shape));
    }

    let mut fields = Vec::with_capacity(headers.len());
    for (name, dtype, offset, shape) in headers {
        let field = format!("field `{name}` ({} {shape:?} at byte offset {offset})", dtype.name());
        let beyond =
            |detail: String| Error::bsdf_format(path, format!("{field} {detail}, but the file is {len} bytes"));
        let elements = shape
            .iter()
            .try_fold(1u64, |product, &n| product.checked_mul(n))
            .ok_or_else(|| beyond("has more elements than 2^64".into()))?;
        let byte_len = elements
            .checked_mul(dtype.size() as u64)
            .ok_or_else(|| beyond(format!("claims {elements} elements, more than 2^64 bytes")))?;
        let end = offset
            .checked_add(byte_len)
            .ok_or_else(|| beyond(format!("claims {elements} elements ({byte_len} bytes), past 2^64")))?;
        if end > len {
            return Err(beyond(format!(
                "claims {elements} elements ({byte_len} bytes) ending at byte {end}"
            )));
        }
        if end > MAX_BYTES {
            return Err(Error::bsdf_format(
                path,
                format!(
                    "{field} claims {elements} elements ({byte_len} bytes) ending at byte {end}, past the \
                     {MAX_BYTES} bytes (256 MiB) frenbrdf reads of a tensor file (the RGL files are a few MB)"
                ),
            ));
        }
        // `end` is at most MAX_BYTES, so every size below fits in a usize.
        fields.push(Field {
            name,
            dtype,
            shape: shape.iter().map(|&n| n as usize).collect(),
            offset: offset as usize,
            byte_len: byte_len as usize,
        });
    }
    Ok(fields)
}

/// Reads the header front to back from a file of `len` bytes, naming what is missing when
/// the file ends early.
struct Cursor<'a, R> {
    path: &'a Path,
    source: R,
    len: u64,
    at: u64,
}

impl<R: Read> Cursor<'_, R> {
    /// The next `n` bytes (`n` < 2^20: a name or a shape at most).
    fn take(&mut self, n: usize, what: &str) -> Result<Vec<u8>> {
        let truncated = |at: u64, len: u64| {
            Error::bsdf_format(
                self.path,
                format!("truncated: {what} needs {n} bytes at byte offset {at}, but the file is {len} bytes"),
            )
        };
        let end = self.at + n as u64;
        if end > self.len {
            return Err(truncated(self.at, self.len));
        }
        if end > MAX_BYTES {
            return Err(Error::bsdf_format(
                self.path,
                format!(
                    "the header runs past byte {MAX_BYTES} (256 MiB) at {what}: more than frenbrdf reads of a \
                     tensor file (the RGL files are a few MB)"
                ),
            ));
        }
        let mut taken = vec![0; n];
        self.source.read_exact(&mut taken).map_err(|e| match e.kind() {
            // The file shrank since its length was read.
            ErrorKind::UnexpectedEof => truncated(self.at, self.at),
            _ => Error::io(self.path, e),
        })?;
        self.at = end;
        Ok(taken)
    }

    fn u8(&mut self, what: &str) -> Result<u8> {
        Ok(self.take(1, what)?[0])
    }
    fn u16(&mut self, what: &str) -> Result<u16> {
        Ok(u16::from_le_bytes(self.take(2, what)?.try_into().expect("2 bytes")))
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }
}

/// One field to write with [`encode`]: name, dtype, shape and little-endian data.
pub struct FieldData<'a> {
    pub name: &'a str,
    pub dtype: Dtype,
    pub shape: &'a [usize],
    pub data: &'a [u8],
}

/// The bytes of a tensor file holding `fields`, each field's data 8-byte aligned as in
/// the RGL files. Panics if a field's data length does not match its shape.
pub fn encode(fields: &[FieldData<'_>]) -> Vec<u8> {
    let header_len: usize = PREAMBLE_BYTES
        + fields
            .iter()
            .map(|f| 2 + f.name.len() + 2 + 1 + 8 + 8 * f.shape.len())
            .sum::<usize>();
    let align = |n: usize| n.div_ceil(8) * 8;
    let mut header = Vec::with_capacity(header_len);
    header.extend_from_slice(MAGIC);
    header.extend_from_slice(&VERSION);
    header.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    let mut offset = align(header_len);
    for field in fields {
        assert_eq!(
            field.data.len(),
            field.shape.iter().product::<usize>() * field.dtype.size(),
            "data of field `{}` does not match its shape",
            field.name
        );
        header.extend_from_slice(&(field.name.len() as u16).to_le_bytes());
        header.extend_from_slice(field.name.as_bytes());
        header.extend_from_slice(&(field.shape.len() as u16).to_le_bytes());
        header.push(field.dtype as u8);
        header.extend_from_slice(&(offset as u64).to_le_bytes());
        for &n in field.shape {
            header.extend_from_slice(&(n as u64).to_le_bytes());
        }
        offset = align(offset + field.data.len());
    }
    let mut bytes = header;
    for field in fields {
        bytes.resize(align(bytes.len()), 0);
        bytes.extend_from_slice(field.data);
    }
    bytes
}

/// Little-endian bytes of `f32` values, for [`encode`].
pub fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::FileExt;

    use super::*;

    fn sample_fields() -> (Vec<f32>, Vec<u8>) {
        ((0..24).map(|i| i as f32 * 0.5 - 3.0).collect(), b"a material".to_vec())
    }

    fn sample_file() -> Vec<u8> {
        let (values, text) = sample_fields();
        encode(&[
            FieldData {
                name: "values",
                dtype: Dtype::Float32,
                shape: &[2, 3, 4],
                data: &f32_bytes(&values),
            },
            FieldData {
                name: "description",
                dtype: Dtype::UInt8,
                shape: &[text.len()],
                data: &text,
            },
            FieldData {
                name: "empty",
                dtype: Dtype::Float64,
                shape: &[0, 5],
                data: &[],
            },
        ])
    }

    fn parse(bytes: Vec<u8>) -> Result<TensorFile> {
        TensorFile::parse(Path::new("test.bsdf"), bytes)
    }

    fn format_message(result: Result<TensorFile>) -> String {
        match result {
            Err(Error::BsdfFormat { path, message }) => {
                assert_eq!(path, Path::new("test.bsdf"));
                message
            }
            Err(other) => panic!("expected a BsdfFormat error, got {other:?}"),
            Ok(_) => panic!("expected a BsdfFormat error, the file parsed"),
        }
    }

    /// Offset of the first byte of field `index`'s header in `sample_file()`.
    fn field_header_offset(index: usize) -> usize {
        let sizes = [
            2 + 6 + 2 + 1 + 8 + 3 * 8,
            2 + 11 + 2 + 1 + 8 + 8,
            2 + 5 + 2 + 1 + 8 + 2 * 8,
        ];
        PREAMBLE_BYTES + sizes[..index].iter().sum::<usize>()
    }

    #[test]
    fn round_trip() {
        let file = parse(sample_file()).unwrap();
        let names: Vec<&str> = file.fields().iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["values", "description", "empty"]);
        let (shape, values) = file.f32_values("values", 3).unwrap();
        assert_eq!((shape, values), (vec![2, 3, 4], sample_fields().0));
        let description = file.require("description", Dtype::UInt8, 1).unwrap();
        assert_eq!(file.data(description), b"a material");
        let empty = file.field("empty").unwrap();
        assert!(empty.is_empty() && file.data(empty).is_empty());
        for field in file.fields() {
            assert_eq!(field.offset % 8, 0);
        }
    }

    #[test]
    fn reads_from_disk_and_reports_missing_files() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("a.bsdf");
        std::fs::write(&path, sample_file()).unwrap();
        let file = TensorFile::read(&path).unwrap();
        assert_eq!(file.path(), path);
        assert_eq!(file.fields().len(), 3);
        match TensorFile::read(&folder.path().join("missing.bsdf")) {
            Err(Error::Io { source, .. }) => assert_eq!(source.kind(), ErrorKind::NotFound),
            other => panic!("expected a NotFound error, got {other:?}"),
        }
        assert!(matches!(TensorFile::read(folder.path()), Err(Error::Io { .. })));
    }

    #[test]
    fn wrong_magic() {
        let mut bytes = sample_file();
        bytes[..12].copy_from_slice(b"tensor_fila\0");
        assert!(format_message(parse(bytes)).contains("not a tensor file"));
        assert!(format_message(parse(b"MERL".to_vec())).contains("truncated: the magic number"));
    }

    #[test]
    fn wrong_version() {
        for version in [[2, 0], [1, 1], [0, 9]] {
            let mut bytes = sample_file();
            bytes[12..14].copy_from_slice(&version);
            let message = format_message(parse(bytes));
            assert!(
                message.contains(&format!("version {}.{} is not supported", version[0], version[1])),
                "{message}"
            );
        }
    }

    #[test]
    fn truncated_anywhere() {
        let bytes = sample_file();
        // Every cut inside the header, and cuts through each field's data.
        let data_start = parse(bytes.clone()).unwrap().fields()[0].offset;
        let cuts = (0..data_start).chain([data_start + 1, data_start + 50, bytes.len() - 1]);
        for cut in cuts {
            let message = format_message(parse(bytes[..cut].to_vec()));
            assert!(
                message.contains("truncated") || message.contains("but the file is"),
                "cut at {cut}: {message}"
            );
        }
        // Cuts at known places name what is missing.
        let cases = [
            (13, "the version"),
            (16, "the field count"),
            (PREAMBLE_BYTES + 1, "the name length of field 0"),
            (PREAMBLE_BYTES + 5, "the name of field 0"),
            (field_header_offset(1) - 3, "the 3-dimensional shape of field `values`"),
            (field_header_offset(1) + 10, "the name of field 1"),
            (field_header_offset(2) + 9, "the dtype of field `empty`"),
            (field_header_offset(2) + 12, "the data offset of field `empty`"),
        ];
        for (cut, what) in cases {
            let message = format_message(parse(bytes[..cut].to_vec()));
            assert!(message.contains(what), "cut at {cut}: {message}");
        }
        let description = parse(bytes.clone()).unwrap().fields()[1].offset;
        let message = format_message(parse(bytes[..description + 5].to_vec()));
        assert!(message.contains("field `description`"), "{message}");
    }

    #[test]
    fn absurd_sizes_are_rejected_without_allocating() {
        // 2^60 elements: the byte count fits in u64 but not in the file; 2^62 float32
        // elements overflow the byte count; 2^40 × 2^40 × 2^40 the element count.
        let shape_at = field_header_offset(1) - 3 * 8;
        let cases = [
            (
                [1u64 << 60, 1, 1],
                "claims 1152921504606846976 elements (4611686018427387904 bytes)",
            ),
            ([1 << 20, 1 << 20, 1 << 20], "claims 1152921504606846976 elements"),
            ([1 << 62, 1, 1], "more than 2^64 bytes"),
            ([1 << 40, 1 << 40, 1 << 40], "more elements than 2^64"),
        ];
        for (dims, expected) in cases {
            let mut bytes = sample_file();
            for (k, n) in dims.iter().enumerate() {
                bytes[shape_at + 8 * k..shape_at + 8 * k + 8].copy_from_slice(&n.to_le_bytes());
            }
            let message = format_message(parse(bytes));
            assert!(message.contains(expected), "{message}");
        }

        // An offset near 2^64.
        let mut bytes = sample_file();
        let offset_at = shape_at - 8;
        bytes[offset_at..offset_at + 8].copy_from_slice(&(u64::MAX - 4).to_le_bytes());
        assert!(format_message(parse(bytes)).contains("past 2^64"));

        // A field count of 2^32 − 1 is refused as such; one of 4 with three fields present
        // fails at the fourth.
        let mut bytes = sample_file();
        bytes[14..18].copy_from_slice(&u32::MAX.to_le_bytes());
        let message = format_message(parse(bytes));
        assert!(message.contains("declares 4294967295 fields"), "{message}");
        let mut bytes = sample_file();
        bytes[14..18].copy_from_slice(&4u32.to_le_bytes());
        bytes.truncate(field_header_offset(3));
        let message = format_message(parse(bytes));
        assert!(
            message.contains("truncated: the name length of field 3 (of 4)"),
            "{message}"
        );
    }

    /// A file of `len` bytes (sparse: nothing is written past `head`) starting with `head`.
    fn sparse_file(folder: &Path, name: &str, head: &[u8], len: u64) -> PathBuf {
        let path = folder.join(name);
        std::fs::write(&path, head).unwrap();
        File::options().write(true).open(&path).unwrap().set_len(len).unwrap();
        path
    }

    fn read_message(path: &Path) -> String {
        match TensorFile::read(path) {
            Err(Error::BsdfFormat { path: named, message }) => {
                assert_eq!(named, path);
                message
            }
            other => panic!("expected a BsdfFormat error, got {other:?}"),
        }
    }

    #[test]
    fn large_files_are_refused_from_their_header() {
        // 20 GB of zeros, random bytes, and a valid header declaring 16 GB: each is refused
        // after reading its header (a whole-file read would abort on the allocation).
        let folder = tempfile::tempdir().unwrap();
        let huge = 20 << 30;
        let zeros = sparse_file(folder.path(), "zeros.bsdf", &[], huge);
        assert!(read_message(&zeros).contains("not a tensor file"));
        let noise: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        let noise = sparse_file(folder.path(), "noise.bsdf", &noise, huge);
        assert!(read_message(&noise).contains("not a tensor file"));

        let mut header = sample_file();
        let shape_at = field_header_offset(1) - 3 * 8;
        for (k, n) in [1u64 << 32, 1, 1].iter().enumerate() {
            header[shape_at + 8 * k..shape_at + 8 * k + 8].copy_from_slice(&n.to_le_bytes());
        }
        let declares = sparse_file(folder.path(), "declares.bsdf", &header, huge);
        let message = read_message(&declares);
        assert!(
            message.contains("field `values`") && message.contains(&format!("past the {MAX_BYTES} bytes")),
            "{message}"
        );

        // A header longer than MAX_BYTES: empty fields of rank 2^16 − 1 (half a MB of
        // shape each, zeros the sparse file reads as), written where each one starts.
        let mut preamble = Vec::from(&MAGIC[..]);
        preamble.extend_from_slice(&VERSION);
        preamble.extend_from_slice(&MAX_FIELDS.to_le_bytes());
        let long = sparse_file(folder.path(), "long.bsdf", &preamble, huge);
        let file = File::options().write(true).open(&long).unwrap();
        let field_len = 2 + 4 + 2 + 1 + 8 + 8 * u16::MAX as u64;
        for index in 0..=MAX_BYTES / field_len {
            let mut header = 4u16.to_le_bytes().to_vec();
            header.extend_from_slice(format!("{index:04}").as_bytes());
            header.extend_from_slice(&u16::MAX.to_le_bytes());
            header.push(Dtype::UInt8 as u8);
            header.extend_from_slice(&0u64.to_le_bytes());
            file.write_all_at(&header, PREAMBLE_BYTES as u64 + index * field_len)
                .unwrap();
        }
        let message = read_message(&long);
        assert!(
            message.contains(&format!("the header runs past byte {MAX_BYTES}")),
            "{message}"
        );

        // A valid file with a gigabyte of anything after its data reads: only the data
        // are read.
        let bytes = sample_file();
        let padded = sparse_file(folder.path(), "padded.bsdf", &bytes, 1 << 30);
        let file = TensorFile::read(&padded).unwrap();
        assert_eq!(file.f32_values("values", 3).unwrap().1, sample_fields().0);
        assert!(file.bytes.len() <= bytes.len());
    }

    #[test]
    fn bad_dtype_code_names_and_duplicates() {
        let mut bytes = sample_file();
        let dtype_at = field_header_offset(0) + 2 + 6 + 2;
        bytes[dtype_at] = 12;
        assert!(format_message(parse(bytes.clone())).contains("unknown dtype code 12"));
        bytes[dtype_at] = 0;
        assert!(format_message(parse(bytes)).contains("unknown dtype code 0"));

        let mut bytes = sample_file();
        bytes[field_header_offset(0) + 2] = 0xff;
        assert!(format_message(parse(bytes)).contains("not UTF-8"));

        let twice = encode(&[
            FieldData {
                name: "a",
                dtype: Dtype::UInt8,
                shape: &[1],
                data: &[1],
            },
            FieldData {
                name: "a",
                dtype: Dtype::UInt8,
                shape: &[1],
                data: &[2],
            },
        ]);
        assert!(format_message(parse(twice)).contains("appears twice"));
    }

    #[test]
    fn require_checks_dtype_and_rank() {
        let file = parse(sample_file()).unwrap();
        let message = file.require("values", Dtype::Float64, 3).unwrap_err().to_string();
        assert!(
            message.contains("float32 with shape [2, 3, 4]; expected float64"),
            "{message}"
        );
        assert!(file.f32_values("values", 2).is_err());
        assert!(file
            .require("nothing", Dtype::UInt8, 1)
            .unwrap_err()
            .to_string()
            .contains("no field `nothing`"));
        assert_eq!(
            (1..=11).map(|c| Dtype::from_code(c).unwrap().size()).sum::<usize>(),
            1 + 1 + 2 + 2 + 4 + 4 + 8 + 8 + 2 + 4 + 8
        );
    }
}
