//! The sizes a linear filter runs at: the allocations it needs ([`FilterAllocator`]) and how
//! its covariance products are formed for fixed and for dynamic sizes ([`FilterDim`]).

use crate::linalg::{mul_tr, mul_tr_add};
use crate::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, SMatrix, U1};

/// Declares [`FilterAllocator`] and its blanket impl from one list of bounds, so that the
/// trait's requirements and what implements it cannot drift apart.
macro_rules! filter_allocator {
    ($(#[$meta:meta])* $($bound:path),+ $(,)?) => {
        $(#[$meta])*
        pub trait FilterAllocator<N: Dim, M: Dim>: $($bound +)+ {}

        impl<N: Dim, M: Dim, A> FilterAllocator<N, M> for A where A: $($bound +)+ {}
    };
}

filter_allocator!(
    /// The nalgebra allocations of a filter with `N` states and `M` measurements. Every pair of
    /// fixed sizes has them, and with the `alloc` feature `(Dyn, Dyn)` too; one bound instead of
    /// six on every generic item.
    Allocator<N, N>,
    Allocator<N, M>,
    Allocator<M, N>,
    Allocator<M, M>,
    Allocator<N>,
    Allocator<M>,
    Allocator<U1, N>,
    Allocator<U1, M>,
);

/// How a filter with `Self` states and `M` measurements forms the products `aᵀ b` of its
/// covariance recursion, the only place where fixed and dynamic sizes need different code.
///
/// Fixed sizes (`Const<N>`, the chip) use the register-blocked kernels of [`crate::linalg`]
/// ([`mul_tr`], [`mul_tr_add`]), which need the column length as a compile-time constant to be
/// fast (see `dot4x2`). Dynamic sizes (`Dyn`, the host, with the `alloc` feature) use plain
/// loops. Both sum every element in the same order, `k` ascending, so they give the same bits.
// The allocator bound sits on the trait, not on its methods: a method-level bound would shadow
// nalgebra's impls inside the fixed-size impl, and `OMatrix<T, Const<N>, Const<N>>` would no
// longer be known there as the `SMatrix` the kernels take.
pub trait FilterDim<M: Dim>: Dim
where
    DefaultAllocator: FilterAllocator<Self, M>,
{
    /// `out = aᵀ b` (`out += aᵀ b` when `add`), for `N × N` operands; only the upper triangle
    /// (and at most one row below it) when `upper`.
    fn mul_tr_nn<T: Real>(
        a: &OMatrix<T, Self, Self>,
        b: &OMatrix<T, Self, Self>,
        out: &mut OMatrix<T, Self, Self>,
        upper: bool,
        add: bool,
    );

    /// `out = aᵀ b` for an `N × N` `a` and an `N × M` `b`.
    fn mul_tr_nm<T: Real>(a: &OMatrix<T, Self, Self>, b: &OMatrix<T, Self, M>, out: &mut OMatrix<T, Self, M>);

    /// `out = aᵀ b` for `N × M` operands.
    fn mul_tr_mm<T: Real>(a: &OMatrix<T, Self, M>, b: &OMatrix<T, Self, M>, out: &mut OMatrix<T, M, M>);
}

impl<const N: usize, const M: usize> FilterDim<Const<M>> for Const<N> {
    #[inline]
    fn mul_tr_nn<T: Real>(
        a: &SMatrix<T, N, N>,
        b: &SMatrix<T, N, N>,
        out: &mut SMatrix<T, N, N>,
        upper: bool,
        add: bool,
    ) {
        if add {
            mul_tr_add(a, b, out, upper);
        } else {
            mul_tr(a, b, out, upper);
        }
    }

    #[inline]
    fn mul_tr_nm<T: Real>(a: &SMatrix<T, N, N>, b: &SMatrix<T, N, M>, out: &mut SMatrix<T, N, M>) {
        mul_tr(a, b, out, false);
    }

    #[inline]
    fn mul_tr_mm<T: Real>(a: &SMatrix<T, N, M>, b: &SMatrix<T, N, M>, out: &mut SMatrix<T, M, M>) {
        mul_tr(a, b, out, false);
    }
}

#[cfg(feature = "alloc")]
impl FilterDim<nalgebra::Dyn> for nalgebra::Dyn {
    fn mul_tr_nn<T: Real>(
        a: &nalgebra::DMatrix<T>,
        b: &nalgebra::DMatrix<T>,
        out: &mut nalgebra::DMatrix<T>,
        upper: bool,
        add: bool,
    ) {
        mul_tr_loops(a, b, out, upper, add);
    }

    fn mul_tr_nm<T: Real>(a: &nalgebra::DMatrix<T>, b: &nalgebra::DMatrix<T>, out: &mut nalgebra::DMatrix<T>) {
        mul_tr_loops(a, b, out, false, false);
    }

    fn mul_tr_mm<T: Real>(a: &nalgebra::DMatrix<T>, b: &nalgebra::DMatrix<T>, out: &mut nalgebra::DMatrix<T>) {
        mul_tr_loops(a, b, out, false, false);
    }
}

/// `out (+)= aᵀ b` by plain loops, each element summed with `k` ascending (the order of the
/// fixed-size kernels); on the upper triangle only when `upper`. Shapes the caller has checked.
#[cfg(feature = "alloc")]
fn mul_tr_loops<T: Real>(
    a: &nalgebra::DMatrix<T>,
    b: &nalgebra::DMatrix<T>,
    out: &mut nalgebra::DMatrix<T>,
    upper: bool,
    add: bool,
) {
    let (k_len, rows, cols) = (a.nrows().min(b.nrows()), a.ncols().min(out.nrows()), b.ncols().min(out.ncols()));
    for j in 0..cols {
        let (bj, last) = (b.column(j), if upper { (j + 1).min(rows) } else { rows });
        for i in 0..last {
            let ai = a.column(i);
            let mut s = T::zero();
            for k in 0..k_len {
                s += ai[k] * bj[k];
            }
            if add {
                out[(i, j)] += s;
            } else {
                out[(i, j)] = s;
            }
        }
    }
}
