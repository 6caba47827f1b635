//! The `eval_flat` / `eval_into` dispatch of an emitted module: one match arm per kernel that
//! calls it with the named inputs and flattens its outputs row-major (the order
//! [`crate::kernels::KernelDef`] documents), so callers that hold a kernel by name (`eval`,
//! `bench`, the interpreter comparison tests) need no per-kernel code.

use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};

use super::*;

/// `v.push(x)` / `v.extend(x.iter().flatten()…copied())` for an array of rank `rank`.
fn flatten_push(x: TokenStream, rank: usize) -> TokenStream {
    match rank {
        0 => quote!(v.push(#x);),
        1 => quote!(v.extend_from_slice(&#x);),
        _ => {
            let flats = (1..rank).map(|_| quote!(.flatten()));
            quote!(v.extend(#x.iter() #(#flats)* .copied());)
        }
    }
}

/// Tokens of the match arm of kernel `k` in `eval_flat`.
pub(super) fn eval_flat_arm(k: &KernelDef) -> TokenStream {
    let fname = Ident::new(&k.name, Span::call_site());
    let name = k.name.as_str();
    let mut decls = Vec::new();
    let mut args: Vec<TokenStream> = k
        .inputs
        .iter()
        .map(|a| match a {
            Arg::Q => quote!(q),
            Arg::Qd => quote!(qd),
            Arg::Omega => quote!(omega),
            Arg::Eps => quote!(eps),
            Arg::Qdd | Arg::Tau => quote!(u),
            Arg::P => quote!(p),
        })
        .collect();
    let mut pushes = Vec::new();
    for o in &k.outputs {
        let id = format_ident!("out_{}", o.name);
        match &o.kind {
            OutKind::Scalar => {
                decls.push(quote!(let mut #id = 0.0;));
                pushes.push(quote!(v.push(#id);));
            }
            OutKind::Array(dims) => {
                let mut init = quote!(0.0);
                for &d in dims.iter().rev() {
                    let dt = dim_tokens(d);
                    init = quote!([#init; #dt]);
                }
                decls.push(quote!(let mut #id = #init;));
                pushes.push(flatten_push(quote!(#id), dims.len()));
            }
            OutKind::Contact => {
                decls.push(quote!(let mut #id = Contact::default();));
                for (field, dims, _) in CONTACT_FIELDS {
                    let f = Ident::new(field, Span::call_site());
                    pushes.push(flatten_push(quote!(#id.#f), dims.len()));
                }
            }
        }
        args.push(quote!(&mut #id));
    }
    quote! {
        #name => {
            #(#decls)*
            #fname(#(#args),*);
            #(#pushes)*
        }
    }
}

/// Tokens of the match arm of kernel `k` (index `idx`) in `eval_index_into`: outputs on the
/// stack, copied into `out` (no allocation).
pub(super) fn eval_into_arm(idx: usize, k: &KernelDef, nq: usize) -> TokenStream {
    let fname = Ident::new(&k.name, Span::call_site());
    let idx = Literal::usize_unsuffixed(idx);
    let total: usize = k.outputs.iter().map(|o| o.ids.len()).sum();
    let total_l = Literal::usize_unsuffixed(total);
    let mut decls = Vec::new();
    let mut copies = Vec::new();
    let mut args: Vec<TokenStream> = k
        .inputs
        .iter()
        .map(|a| match a {
            Arg::Q => quote!(q),
            Arg::Qd => quote!(qd),
            Arg::Omega => quote!(omega),
            Arg::Eps => quote!(eps),
            Arg::Qdd | Arg::Tau => quote!(u),
            Arg::P => quote!(p),
        })
        .collect();
    let mut off = 0usize;
    let copy = |x: TokenStream, dims: &[Dim], off: &mut usize| -> TokenStream {
        let len: usize = dims.iter().map(|&d| dim_value(d, nq)).product();
        let (a, b) = (
            Literal::usize_unsuffixed(*off),
            Literal::usize_unsuffixed(*off + len),
        );
        *off += len;
        match dims.len() {
            0 => quote!(out[#a] = #x;),
            1 => quote!(out[#a..#b].copy_from_slice(&#x);),
            r => {
                let flats = (1..r).map(|_| quote!(.flatten()));
                quote! {
                    for (d, s) in out[#a..#b].iter_mut().zip(#x.iter() #(#flats)*) {
                        *d = *s;
                    }
                }
            }
        }
    };
    for o in &k.outputs {
        let id = format_ident!("out_{}", o.name);
        match &o.kind {
            OutKind::Scalar => {
                decls.push(quote!(let mut #id = 0.0;));
                copies.push(copy(quote!(#id), &[], &mut off));
            }
            OutKind::Array(dims) => {
                let mut init = quote!(0.0);
                for &d in dims.iter().rev() {
                    let dt = dim_tokens(d);
                    init = quote!([#init; #dt]);
                }
                decls.push(quote!(let mut #id = #init;));
                copies.push(copy(quote!(#id), dims, &mut off));
            }
            OutKind::Contact => {
                decls.push(quote!(let mut #id = Contact::default();));
                for (field, dims, _) in CONTACT_FIELDS {
                    let f = Ident::new(field, Span::call_site());
                    copies.push(copy(quote!(#id.#f), dims, &mut off));
                }
            }
        }
        args.push(quote!(&mut #id));
    }
    quote! {
        #idx => {
            if out.len() < #total_l {
                return None;
            }
            #(#decls)*
            #fname(#(#args),*);
            #(#copies)*
            Some(#total_l)
        }
    }
}
