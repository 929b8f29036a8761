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
    // Constant weights are converted once, here, so that later operators (PRELU above all)
    // see a constant they can specialise on.
    if let Some(konst) = op.ctx.target.outlet_fact(op.inputs[0])?.konst.clone() {
        let converted = konst.cast_to::<f32>()?.into_owned();
        return Ok(tvec!(op.ctx.target.add_const(op.prefix, converted)?));
    }
    op.ctx.target.wire_node(op.prefix, cast(f32::datum_type()), op.inputs)
}

/// `max(x, 0) + alpha · min(x, 0)`.
///
/// With a constant per-channel alpha (the usual case, and every PRELU of MediaPipe's face
/// models) this is one pass of [`ChannelPrelu`]: spelled as four broadcast operators, tract
/// fuses some but evaluates the rest with generic broadcasting, which took a third of the
/// landmark network's time.
fn de_prelu(op: &mut DeserOp) -> TractResult<TVec<OutletId>> {
    let (x, alpha) = (op.inputs[0], op.inputs[1]);
    let x_fact = op.ctx.target.outlet_fact(x)?.clone();
    let alpha_fact = op.ctx.target.outlet_fact(alpha)?.clone();
    if let (Some(konst), Some(channels)) = (alpha_fact.konst.as_ref(), x_fact.shape.last().and_then(|d| d.to_usize().ok())) {
        let per_channel = konst.datum_type() == f32::datum_type()
            && x_fact.datum_type == f32::datum_type()
            && konst.len() == channels
            && konst.shape().last() == Some(&channels)
            && konst.rank() <= x_fact.rank();
        if per_channel {
            let alpha = konst.to_plain_array_view::<f32>()?.iter().map(|a| a.to_bits()).collect();
            return op.ctx.target.wire_node(op.prefix, ChannelPrelu { alpha_bits: alpha }, &[x]);
        }
    }
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

/// PReLU with one alpha per channel of the last axis, in a single in-place pass.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ChannelPrelu {
    /// Alpha per channel, as `f32::to_bits` so the op can be `Eq`.
    alpha_bits: Vec<u32>,
}

impl Op for ChannelPrelu {
    fn name(&self) -> StaticName {
        "ChannelPrelu".into()
    }

    op_as_typed_op!();
}

impl EvalOp for ChannelPrelu {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let alpha: Vec<f32> = self.alpha_bits.iter().map(|&b| f32::from_bits(b)).collect();
        let mut x = args_1!(inputs).into_tensor();
        let mut view = x.to_plain_array_view_mut::<f32>()?;
        let Some(values) = view.as_slice_mut() else {
            bail!("ChannelPrelu needs a contiguous tensor");
        };
        // Alpha repeated to a block of at least 256 values, so the inner loop is long and
        // branch-free enough to vectorise whatever the channel count.
        let repeats = 256usize.div_ceil(alpha.len()).max(1);
        let tiled: Vec<f32> = alpha.iter().copied().cycle().take(alpha.len() * repeats).collect();
        let mut blocks = values.chunks_exact_mut(tiled.len());
        // A select, not `max`/`min` (whose NaN rules keep the loop from vectorising).
        let prelu = |v: &mut f32, a: &f32| {
            let x = *v;
            *v = if x < 0.0 { x * a } else { x };
        };
        for block in &mut blocks {
            block.iter_mut().zip(&tiled).for_each(|(v, a)| prelu(v, a));
        }
        blocks
            .into_remainder()
            .iter_mut()
            .zip(&tiled)
            .for_each(|(v, a)| prelu(v, a));
        Ok(tvec!(x.into_tvalue()))
    }
}

impl TypedOp for ChannelPrelu {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        Ok(tvec!(inputs[0].without_value()))
    }

    as_op!();
}
