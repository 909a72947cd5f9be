"""Working arrays made inside kernels: :func:`scratch`, numba's ``np.empty`` without its baggage.

A kernel that calls ``np.empty`` or ``np.zeros`` compiles numba's implementations of them as
functions of their own, and loading the cached kernel then rebuilds their environments, which
imports ``numba.np.arrayobj`` and what it drags in (sorting, slicing, unicode): 0.05 s of a
one-shot convert. :func:`scratch` emits the same allocation inline while compiling, so the
cached machine code refers to no numba module. Allocating inside the kernel (rather than
passing working arrays in) also lets LLVM know they alias nothing else: with arrays passed in,
the resampling kernel ran 17–40 % slower.
"""

from .._jit import intrinsic

__all__ = ["scratch"]


@intrinsic
def scratch(typingctx, shape, dtype):
    """A new, uninitialised C-contiguous array of ``shape`` (an integer or a tuple of integers)
    and ``dtype`` (a numpy scalar type such as ``np.float64``), for use inside a kernel."""
    from numba import types  # runs while compiling only, with numba imported

    if isinstance(shape, types.Integer):
        ndim = 1
    elif isinstance(shape, types.BaseTuple) and all(isinstance(t, types.Integer) for t in shape):
        ndim = shape.count
    else:
        return None
    if not isinstance(dtype, types.NumberClass):
        return None
    array_type = types.Array(dtype.instance_type, ndim, "C")

    def codegen(context, builder, signature, args):
        # numba's own _empty_nd_impl compiles an allocator trampoline (a function of
        # numba.np.arrayobj, whose environment a cached kernel would rebuild); this emits the
        # allocation itself. The helpers imported here run while compiling only.
        from llvmlite import ir
        from numba.core import cgutils
        from numba.np.arrayobj import _parse_shape, make_array, populate_array

        shapes = _parse_shape(context, builder, signature.args[0], args[0])
        data_type = context.get_data_type(array_type.dtype)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(data_type))
        count = context.get_constant(types.intp, 1)
        overflow = ir.Constant(ir.IntType(1), 0)
        for extent in (*shapes, itemsize):
            product = builder.smul_with_overflow(count, extent)
            count = builder.extract_value(product, 0)
            overflow = builder.or_(overflow, builder.extract_value(product, 1))
        with builder.if_then(overflow, likely=False):
            context.call_conv.return_user_exc(builder, ValueError, ("scratch array too big",))
        align = context.get_preferred_array_alignment(array_type.dtype)
        meminfo = context.nrt.meminfo_alloc_aligned(
            builder, count, context.get_constant(types.uint32, align)
        )
        strides = [itemsize]
        for extent in reversed(shapes[1:]):
            strides.append(builder.mul(strides[-1], extent))
        intp = context.get_value_type(types.intp)
        array = make_array(array_type)(context, builder)
        populate_array(
            array,
            data=builder.bitcast(context.nrt.meminfo_data(builder, meminfo), data_type.as_pointer()),
            shape=cgutils.pack_array(builder, shapes, ty=intp),
            strides=cgutils.pack_array(builder, list(reversed(strides)), ty=intp),
            itemsize=itemsize,
            meminfo=meminfo,
        )
        return array._getvalue()

    return array_type(shape, dtype), codegen
