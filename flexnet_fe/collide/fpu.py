"""Flush subnormal floats to zero inside the collision kernel (x86-64 MXCSR FTZ + DAZ bits).

Why: the held net starts exactly at rest, and an explicit mass–spring step carries a disturbance
one node further per step with an amplitude shrinking by ~(ω dt)² per node, so after a few dozen
nodes the velocities ahead of the physical wave front are subnormal (< 2.2e-308). x86 arithmetic on
subnormals is ~30–100× slower: measured here, the collision loop went from 0.03 ms to 3 ms per
step. Flushing them to zero changes no value by more than 2.2e-308 (absolute). ``advance`` sets
the bits on entry and restores the caller's MXCSR on exit, so the rest of the process (numpy,
scipy, dolfinx) is unaffected.
"""

from __future__ import annotations

import platform

from llvmlite import ir
from numba import types
from numba.core.extending import intrinsic

if platform.machine() not in ("x86_64", "AMD64"):  # pragma: no cover - this project runs on x86-64
    raise ImportError(f"flexnet_fe.collide.fpu needs x86-64 (MXCSR); this machine is {platform.machine()}")

FTZ_DAZ = 0x8040
"""MXCSR bits: flush-to-zero (bit 15) and denormals-are-zero (bit 6)."""


@intrinsic
def get_mxcsr(typingctx):
    """The current MXCSR register (uint32); numba intrinsic (llvm.x86.sse.stmxcsr)."""
    def codegen(context, builder, signature, args):
        ptr = builder.alloca(ir.IntType(32))
        i8p = ir.IntType(8).as_pointer()
        fn = builder.module.declare_intrinsic("llvm.x86.sse.stmxcsr", fnty=ir.FunctionType(ir.VoidType(), [i8p]))
        builder.call(fn, [builder.bitcast(ptr, i8p)])
        return builder.load(ptr)
    return types.uint32(), codegen


@intrinsic
def set_mxcsr(typingctx, value):
    """Load ``value`` (uint32) into MXCSR; numba intrinsic (llvm.x86.sse.ldmxcsr)."""
    def codegen(context, builder, signature, args):
        ptr = builder.alloca(ir.IntType(32))
        builder.store(args[0], ptr)
        i8p = ir.IntType(8).as_pointer()
        fn = builder.module.declare_intrinsic("llvm.x86.sse.ldmxcsr", fnty=ir.FunctionType(ir.VoidType(), [i8p]))
        builder.call(fn, [builder.bitcast(ptr, i8p)])
        return context.get_dummy_value()
    return types.void(types.uint32), codegen
