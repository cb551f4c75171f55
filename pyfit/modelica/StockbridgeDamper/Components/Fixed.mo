within StockbridgeDamper.Components;
model Fixed "Translational flange fixed in the inertial frame"
  parameter Real s0(unit="m") = 0 "Fixed position of the flange";
  Interfaces.Flange flange "Flange held at s0; flange.f is the support reaction";
equation
  flange.s = s0;
end Fixed;
