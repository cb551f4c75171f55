within StockbridgeDamper.Components;
model BeamToTranslational "Adapter: the vertical degree of freedom of a beam node as a translational flange (transmits no moment)"
  Interfaces.BeamFlange beam "Beam node";
  Interfaces.Flange flange "Translational flange moving with the node's vertical displacement";
equation
  flange.s = beam.x;
  beam.f + flange.f = 0;
  beam.tau = 0;
end BeamToTranslational;
