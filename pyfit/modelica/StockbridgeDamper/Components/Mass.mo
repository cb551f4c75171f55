within StockbridgeDamper.Components;
model Mass "Sliding point mass with one translational flange"
  parameter Real m(unit="kg", min=0) = 1 "Mass";
  Interfaces.Flange flange "Flange rigidly attached to the mass";
  Real s(unit="m", start=0, nominal=1e-4) "Absolute position";
  Real v(unit="m/s", start=0, nominal=1e-2) "Absolute velocity";
  Real a(unit="m/s2") "Absolute acceleration";
equation
  s = flange.s;
  v = der(s);
  a = der(v);
  m*a = flange.f;
end Mass;
