within StockbridgeDamper;
package Elements "Causal element models for exchange with other FMI tools (in the style of the MSL's Translational.Examples.GenerationOfFMUs): motion in, force out, or force in, motion out"
end Elements;
