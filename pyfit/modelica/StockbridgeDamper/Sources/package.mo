within StockbridgeDamper;
package Sources "Force and motion sources with built-in parameterised excitations"
end Sources;
