//! Operators added in faceanim's patched copy of tract-tflite 0.23.9 (see FACEANIM-PATCH.md):
//! DEQUANTIZE (float16 weights to float32), PRELU, NEG and SQUARED_DIFFERENCE, which
//! MediaPipe's face models use and this version does not map.

use tract_core::internal::*;
use tract_core::ops::cast::cast;
use tract_core::ops::change_axes::wire_with_rank_broadcast;
use tract_core::ops::math;

use crate::registry::{DeserOp, Registry};
use crate::tflite::BuiltinOperator;

pub fn register_all(reg: &mut Registry) {
    reg.reg_to_tract(BuiltinOperator::DEQUANTIZE, de_dequantize);
    reg.reg_to_tract(BuiltinOperator::PRELU, de_prelu);
    reg.reg_to_tract(BuiltinOperator::NEG, |op| op.ctx.target.wire_node(op.prefix, math::neg(), op.inputs));
    reg.reg_to_tract(BuiltinOperator::SQUARED_DIFFERENCE, de_squared_difference);
}

/// Only float16 → float32 (the models store weights as float16); integer dequantisation would
/// need the tensor's quantisation parameters and is refused rather than guessed.
fn de_dequantize(op: &mut DeserOp) -> TractResult<TVec<OutletId>> {
    let input = op.ctx.target.outlet_fact(op.inputs[0])?.datum_type;
    ensure!(input == f16::datum_type(), "DEQUANTIZE from {input:?} is not supported (only f16)");
    op.ctx.target.wire_node(op.prefix, cast(f32::datum_type()), op.inputs)
}

/// `max(x, 0) + alpha · min(x, 0)`.
fn de_prelu(op: &mut DeserOp) -> TractResult<TVec<OutletId>> {
    let (x, alpha) = (op.inputs[0], op.inputs[1]);
    let zero = op.ctx.target.add_const(format!("{}.zero", op.prefix), tensor0(0f32))?;
    let target = &mut *op.ctx.target;
    let positive = wire_with_rank_broadcast(format!("{}.positive", op.prefix), target, math::max(), &[x, zero])?;
    let negative = wire_with_rank_broadcast(format!("{}.negative", op.prefix), target, math::min(), &[x, zero])?;
    let scaled = wire_with_rank_broadcast(format!("{}.scaled", op.prefix), target, math::mul(), &[negative[0], alpha])?;
    wire_with_rank_broadcast(op.prefix, target, math::add(), &[positive[0], scaled[0]])
}

/// `(a − b)²`.
fn de_squared_difference(op: &mut DeserOp) -> TractResult<TVec<OutletId>> {
    let target = &mut *op.ctx.target;
    let difference = wire_with_rank_broadcast(format!("{}.difference", op.prefix), target, math::sub(), op.inputs)?;
    target.wire_node(op.prefix, math::square(), &difference)
}
