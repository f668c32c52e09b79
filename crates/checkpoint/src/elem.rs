//! Fixed-size elements of checkpoint arrays, little-endian.

/// An array element: a fixed number of little-endian bytes.
pub trait Elem: Copy {
    /// Bytes per element.
    const SIZE: usize;
    /// Appends the element's bytes.
    fn put(&self, out: &mut Vec<u8>);
    /// Reads an element from exactly [`Elem::SIZE`] bytes.
    fn get(b: &[u8]) -> Self;
    /// Appends the bytes of every element of `v`.
    #[inline]
    fn put_all(v: &[Self], out: &mut Vec<u8>) {
        for x in v {
            x.put(out);
        }
    }
}

macro_rules! scalar {
    ($t:ty, $n:expr) => {
        impl Elem for $t {
            const SIZE: usize = $n;
            #[inline]
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            #[inline]
            fn get(b: &[u8]) -> Self {
                <$t>::from_le_bytes(b.try_into().expect("element size"))
            }
        }
    };
}

impl Elem for u8 {
    const SIZE: usize = 1;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.push(*self);
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        b[0]
    }
    /// Bytes are copied as they are: a bond-state array goes at memory speed.
    #[inline]
    fn put_all(v: &[Self], out: &mut Vec<u8>) {
        out.extend_from_slice(v);
    }
}
scalar!(u32, 4);
scalar!(u64, 8);
scalar!(f64, 8);

impl<T: Elem + Default, const N: usize> Elem for [T; N] {
    const SIZE: usize = T::SIZE * N;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        for x in self {
            x.put(out);
        }
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        std::array::from_fn(|k| T::get(&b[k * T::SIZE..(k + 1) * T::SIZE]))
    }
}
