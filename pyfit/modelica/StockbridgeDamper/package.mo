within ;
package StockbridgeDamper "Acausal models of hysteretic dampers: Bouc-Wen oscillators and the Stockbridge damper (SI units)"
  annotation(Documentation(info="<html><p>Translational and planar-beam components for
hysteretic devices, and the example systems exported as FMUs: the Bouc-Wen benchmark
oscillator, the two-degree-of-freedom system in four configurations and the
finite-element Stockbridge damper on a shaker. All quantities are SI.</p></html>"));
end StockbridgeDamper;
